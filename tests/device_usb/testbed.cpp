// SPDX-License-Identifier: MIT
#include "testbed.hpp"

#include <algorithm>
#include <stdexcept>

namespace ballbar::device::testing {

Testbed::Testbed() : tb_(umockdev_testbed_new()) {}

Testbed::~Testbed() {
    g_object_unref(tb_);
}

bool Testbed::preload_active() {
    // umockdev_in_mock_environment() is only true once a testbed exists, so look at the preload itself.
    const char* preload = g_getenv("LD_PRELOAD");
    return preload && std::string(preload).find("libumockdev-preload") != std::string::npos;
}

void Testbed::add(const std::string& description) {
    GError* err = nullptr;
    if (!umockdev_testbed_add_from_string(tb_, description.c_str(), &err)) {
        std::string msg = err ? err->message : "unknown error";
        g_clear_error(&err);
        throw std::runtime_error("umockdev: cannot add device: " + msg);
    }
}

void Testbed::remove(const std::string& syspath) {
    umockdev_testbed_uevent(tb_, syspath.c_str(), "remove");
    umockdev_testbed_remove_device(tb_, syspath.c_str());
}

void EchoEndpoint::on_host_bytes(std::span<const std::uint8_t> data) {
    std::lock_guard lock(m_);
    received_.insert(received_.end(), data.begin(), data.end());
    if (!muted_) out_.insert(out_.end(), data.begin(), data.end());
}

std::size_t EchoEndpoint::take_device_bytes(std::span<std::uint8_t> out) {
    std::lock_guard lock(m_);
    const std::size_t n = std::min(out.size(), out_.size());
    std::copy_n(out_.begin(), n, out.begin());
    out_.erase(out_.begin(), out_.begin() + static_cast<std::ptrdiff_t>(n));
    return n;
}

std::vector<std::uint8_t> EchoEndpoint::received() const {
    std::lock_guard lock(m_);
    return received_;
}

void EchoEndpoint::set_muted(bool muted) {
    std::lock_guard lock(m_);
    muted_ = muted;
}

std::string to_hex(std::span<const std::uint8_t> bytes) {
    static const char* digits = "0123456789ABCDEF";
    std::string s;
    for (auto b : bytes) {
        s.push_back(digits[b >> 4]);
        s.push_back(digits[b & 15]);
    }
    return s;
}

}  // namespace ballbar::device::testing
