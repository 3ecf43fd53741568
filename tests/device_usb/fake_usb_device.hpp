// SPDX-License-Identifier: MIT
// A fake vendor-class USB ball-bar for libusb under umockdev: a usbfs node whose ioctls
// (URB submit/reap/discard, claim, capabilities, string descriptors) are answered in this process and
// whose bulk endpoints are wired to a DeviceEndpoint (the emulator, or an echo in simple tests).
// Runs on umockdev's worker thread; plug()/unplug() may be called from the test thread.
#pragma once

#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <vector>

#include "ballbar/device/transport.hpp"
#include "testbed.hpp"

namespace ballbar::device::testing {

class FakeUsbBulkDevice {
  public:
    FakeUsbBulkDevice(Testbed& tb, DeviceEndpoint& endpoint, std::uint16_t vid, std::uint16_t pid, std::string serial,
                      int port = 1);
    ~FakeUsbBulkDevice();
    FakeUsbBulkDevice(const FakeUsbBulkDevice&) = delete;
    FakeUsbBulkDevice& operator=(const FakeUsbBulkDevice&) = delete;

    /// Plugs the device in: adds it to the testbed with a fresh device number and attaches the handler.
    void plug();
    /// Pulls the cable: transfers in flight end with -ESHUTDOWN, further ioctls fail with ENODEV (as the
    /// kernel does), and the device leaves sysfs.
    void unplug();
    /// The usbfs node of the current plug, e.g. /dev/bus/usb/001/002.
    std::string node() const;
    std::string syspath() const;
    /// Number of bulk IN transfers completed so far (to check that data flowed).
    int in_transfers() const;

    struct Urb;     // one submitted URB (client's urb + buffer)
    struct Handle;  // one plug: the ioctl handler object and its generation

  private:
    std::string description() const;
    void pump_locked();
    void complete_locked(Urb* u, int status, int length);
    int control_locked(Urb* u);
    static int on_ioctl(void* handler, void* client, void* user_data);

    Testbed& tb_;
    DeviceEndpoint& endpoint_;
    std::uint16_t vid_;
    std::uint16_t pid_;
    std::string serial_;
    int port_;
    mutable std::mutex m_;
    int devnum_ = 1;
    int generation_ = 0;
    bool present_ = false;
    int in_transfers_ = 0;
    std::deque<Urb*> pending_in_;
    std::deque<Urb*> done_;
    std::vector<Handle*> handles_;
};

}  // namespace ballbar::device::testing
