// SPDX-License-Identifier: MIT
// Modbus RTU indicators (the Shahe type): serial 38400 8N2 by default, slave 1, function 03 on holding
// registers 0x0000–0x0001, a signed 32-bit value in 0.1 µm (docs/instruments.md, "Modbus RTU"). The host
// side is libmodbus.
#include <modbus.h>

#include <cerrno>
#include <cstring>

#include "ballbar/device/gauge.hpp"

namespace ballbar::device::gauge {

Reading modbus_reading(std::uint16_t high, std::uint16_t low) {
    const auto raw = static_cast<std::int32_t>((static_cast<std::uint32_t>(high) << 16) | low);
    Reading r;
    r.value = raw / 10000.0;
    r.decimals = 4;
    return r;
}

namespace {

class ModbusGauge final : public Gauge {
  public:
    ModbusGauge(const std::string& path, int slave, int baud)
        : uri_("modbus:" + path + "?slave=" + std::to_string(slave) + "&baud=" + std::to_string(baud)) {
        ctx_ = modbus_new_rtu(path.c_str(), baud, 'N', 8, 2);
        if (!ctx_) throw DeviceError(DeviceErrorKind::Io, uri_ + ": " + modbus_strerror(errno));
        if (modbus_set_slave(ctx_, slave) != 0) {
            const std::string e = modbus_strerror(errno);
            modbus_free(ctx_);
            throw std::invalid_argument("bad device URI '" + uri_ + "': slave " + std::to_string(slave) + ": " + e);
        }
        modbus_set_byte_timeout(ctx_, 0, 50'000);  // a reply cut off is over after 50 ms of silence
        if (modbus_connect(ctx_) != 0) {
            const int err = errno;
            modbus_free(ctx_);
            const std::string msg = uri_ + ": cannot open the port: " + std::strerror(err);
            if (err == EACCES || err == EPERM) throw DeviceError(DeviceErrorKind::Permission, msg);
            if (err == ENOENT || err == ENODEV || err == ENXIO) throw DeviceError(DeviceErrorKind::NotFound, msg);
            throw DeviceError(DeviceErrorKind::Io, msg);
        }
    }
    ~ModbusGauge() override {
        modbus_close(ctx_);
        modbus_free(ctx_);
    }
    ModbusGauge(const ModbusGauge&) = delete;
    ModbusGauge& operator=(const ModbusGauge&) = delete;

    Identity identify() override {
        Identity id;
        id.kind = Kind::Modbus;
        id.maker = "Modbus RTU indicator";
        id.model = "registers 0-1, int32 / 10000 mm";
        (void)read(std::chrono::milliseconds(1000));  // it answers at all
        return id;
    }

    Reading read(std::chrono::milliseconds timeout) override {
        const auto ms = std::max<long>(1, static_cast<long>(timeout.count()));
        modbus_set_response_timeout(ctx_, static_cast<std::uint32_t>(ms / 1000),
                                    static_cast<std::uint32_t>((ms % 1000) * 1000));
        std::uint16_t regs[2] = {0, 0};
        if (modbus_read_registers(ctx_, 0x0000, 2, regs) == 2) return modbus_reading(regs[0], regs[1]);
        const int err = errno;
        modbus_flush(ctx_);
        Reading r;
        if (err == EMBXSBUSY) {
            r.status = ReadingStatus::NotReady;
            r.code = 6;
            return r;
        }
        if (err == EMBXSFAIL) {
            r.status = ReadingStatus::OutOfRange;
            r.code = 4;
            return r;
        }
        if (err == ETIMEDOUT) throw DeviceError(DeviceErrorKind::Timeout, uri_ + ": no reply (or a reply cut off)");
        if (err == EMBBADCRC || err == EMBBADDATA || err == EMBBADSLAVE || err == EMBBADEXC || err == EMBUNKEXC ||
            err == EMBMDATA)
            throw DeviceError(DeviceErrorKind::Protocol, uri_ + ": " + modbus_strerror(err));
        if (err > MODBUS_ENOBASE && err <= EMBXGTAR) {  // another exception reply
            r.status = ReadingStatus::Error;
            r.code = err - MODBUS_ENOBASE;
            return r;
        }
        if (err == EIO || err == ENXIO || err == EBADF)
            throw DeviceError(DeviceErrorKind::Disconnected, uri_ + ": " + modbus_strerror(err));
        throw DeviceError(DeviceErrorKind::Io, uri_ + ": " + modbus_strerror(err));
    }

    std::string uri() const override { return uri_; }

  private:
    std::string uri_;
    modbus_t* ctx_ = nullptr;
};

}  // namespace

std::unique_ptr<Gauge> open_modbus_gauge(const std::string& path, int slave, int baud) {
    return std::make_unique<ModbusGauge>(path, slave, baud);
}

}  // namespace ballbar::device::gauge
