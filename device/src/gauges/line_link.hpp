// SPDX-License-Identifier: MIT
// Internal: the request/reply loop the ASCII gauge drivers share (Sylvac, Digimatic adaptor): drop what
// an earlier, cut-off reply left, send one command, read until the codec answers Valid or Invalid.
#pragma once

#include <array>
#include <chrono>
#include <string>
#include <string_view>

#include "ballbar/device/gauge.hpp"
#include "ballbar/device/transport.hpp"

namespace ballbar::device::gauge::detail {

/// The first line of `rx` ending in `terminator`: NeedMore without one (Invalid past kMaxLine bytes),
/// Invalid when it holds a control character; Valid with the line (without terminator) in `text`.
Decoded take_line(std::string_view rx, char terminator);

using Codec = Decoded (*)(std::string_view);

/// Sends `command`, returns the codec's Valid answer. Throws DeviceError: Timeout (nothing, or a reply
/// cut off), Protocol (Invalid), and whatever the link throws.
Decoded ask(Transport& link, std::string& rx, std::string_view command, Codec codec, std::chrono::milliseconds timeout);

}  // namespace ballbar::device::gauge::detail
