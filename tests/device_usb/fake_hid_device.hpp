// SPDX-License-Identifier: MIT
// A fake HID ball-bar for hidapi's hidraw backend under umockdev: a hidraw node (a pty underneath)
// with its hid/usb parents in sysfs. Output reports the host writes arrive in the "handle-write" signal
// and are unpacked for the DeviceEndpoint; a pump thread packs the endpoint's bytes into 64-byte input
// reports and writes them to the pty master, where hidapi's read() finds them.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "ballbar/device/transport.hpp"
#include "testbed.hpp"

namespace ballbar::device::testing {

class FakeHidDevice {
  public:
    FakeHidDevice(Testbed& tb, DeviceEndpoint& endpoint, std::uint16_t vid, std::uint16_t pid, std::string serial);
    ~FakeHidDevice();
    FakeHidDevice(const FakeHidDevice&) = delete;
    FakeHidDevice& operator=(const FakeHidDevice&) = delete;

    /// Plugs the device in under a fresh hidraw node (hidraw0, then hidraw1, ...).
    void plug();
    /// Pulls the cable: stops input reports, fails writes with ENODEV and removes the device.
    void unplug();
    std::string node() const;
    /// Output reports received so far.
    int reports_received() const;

    struct Handle;

  private:
    std::string description(int index) const;
    void pump();
    static int on_ioctl(void* handler, void* client, void* user_data);
    static int on_write(void* handler, void* client, void* user_data);

    Testbed& tb_;
    DeviceEndpoint& endpoint_;
    std::uint16_t vid_;
    std::uint16_t pid_;
    std::string serial_;
    mutable std::mutex m_;
    int generation_ = 0;
    bool present_ = false;
    int master_fd_ = -1;
    int reports_received_ = 0;
    std::vector<Handle*> handles_;
    std::atomic<bool> stop_{false};
    std::thread pump_;
};

}  // namespace ballbar::device::testing
