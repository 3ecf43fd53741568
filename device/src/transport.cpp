// SPDX-License-Identifier: MIT
#include "ballbar/device/transport.hpp"

namespace ballbar::device {

const char* to_string(DeviceErrorKind kind) {
    switch (kind) {
        case DeviceErrorKind::NotFound:
            return "not found";
        case DeviceErrorKind::Permission:
            return "permission denied";
        case DeviceErrorKind::Disconnected:
            return "disconnected";
        case DeviceErrorKind::Timeout:
            return "timeout";
        case DeviceErrorKind::Protocol:
            return "protocol error";
        case DeviceErrorKind::Io:
            return "I/O error";
    }
    return "?";
}

}  // namespace ballbar::device
