// SPDX-License-Identifier: MIT
// A fake Mitutoyo USB-ITN cable for libusb under umockdev: a HID-class device (interface 0, interrupt IN
// 0x81, 8-byte reports) whose usbfs ioctls are answered in this process: string descriptors, the vendor
// control transfers (0x40/0xC0) and interrupt-IN transfers, wired to the gauge emulator's USB side.
// Runs on umockdev's worker thread; plug()/unplug() may be called from the test thread.
#pragma once

#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <vector>

#include "ballbar/device/gauge_emulator.hpp"
#include "testbed.hpp"

namespace ballbar::device::testing {

class FakeItnDevice {
  public:
    FakeItnDevice(Testbed& tb, gauge::GaugeEmulator& emulator, std::string serial, int port = 2);
    ~FakeItnDevice();
    FakeItnDevice(const FakeItnDevice&) = delete;
    FakeItnDevice& operator=(const FakeItnDevice&) = delete;

    /// Plugs the device in: adds it to the testbed with a fresh device number and attaches the handler.
    void plug();
    /// Pulls the cable: transfers in flight end with -ESHUTDOWN, further ioctls fail with ENODEV (as the
    /// kernel does), and the device leaves sysfs.
    void unplug();
    /// The usbfs node of the current plug, e.g. /dev/bus/usb/001/002.
    std::string node() const;
    std::string syspath() const;
    /// Number of interrupt IN transfers completed with data so far.
    int in_transfers() const;
    /// Vendor control transfers seen (init, status, commands).
    int vendor_requests() const;

    struct Urb;     // one submitted URB (client's urb + buffer)
    struct Handle;  // one plug: the ioctl handler object and its generation

  private:
    std::string description() const;
    void pump_locked();
    void complete_locked(Urb* u, int status, int length);
    int control_locked(Urb* u);
    static int on_ioctl(void* handler, void* client, void* user_data);

    Testbed& tb_;
    gauge::GaugeEmulator& emu_;
    std::string serial_;
    int port_;
    mutable std::mutex m_;
    int devnum_ = 1;
    int generation_ = 0;
    bool present_ = false;
    int in_transfers_ = 0;
    int vendor_requests_ = 0;
    std::deque<Urb*> pending_in_;
    std::deque<Urb*> done_;
    std::vector<Handle*> handles_;
};

}  // namespace ballbar::device::testing
