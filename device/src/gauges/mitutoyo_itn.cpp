// SPDX-License-Identifier: MIT
// Mitutoyo USB-ITN cable: a HID keyboard by default; through libusb the host initialises it with vendor
// control transfers, sends commands (ASCII + CR) as vendor control transfers and takes the replies from
// the interrupt-IN endpoint (docs/instruments.md, "Mitutoyo USB-ITN").
#include <array>
#include <memory>

#include "ballbar/device/gauge.hpp"
#include "line_link.hpp"

namespace ballbar::device::gauge {

Decoded decode_itn(std::string_view rx) {
    Decoded d = detail::take_line(rx, '\r');
    if (d.result != Decode::Valid) return d;
    const std::string_view t = d.text;
    if (t.size() == 12 && t.substr(0, 3) == "01A" && (t[3] == '+' || t[3] == '-')) {
        // D5..D12: eight characters, digits and one decimal point; D4 the sign.
        if (auto r = parse_decimal(t.substr(3)); r && t.substr(4).find('.') != std::string_view::npos) {
            d.reading = *r;
            return d;
        }
        d.result = Decode::Invalid;
        return d;
    }
    if (t.size() >= 2 && t[0] == '9') {
        if (auto code = parse_decimal(t); code && code->decimals == 0) {
            // Up to 12 digits parse; a code past int is no code we know (found by fuzz_gauge_replies: the
            // conversion was undefined).
            d.reading.code = code->value < 1e9 ? static_cast<int>(code->value) : 999'999'999;
            d.reading.status = d.reading.code == 918   ? ReadingStatus::NotReady
                               : d.reading.code == 911 ? ReadingStatus::OutOfRange
                                                       : ReadingStatus::Error;
            return d;
        }
    }
    if (t.empty() || t.substr(0, 2) == "01") {  // a damaged data line
        d.result = Decode::Invalid;
        return d;
    }
    d.reading.status = ReadingStatus::Error;  // an answer in `text` (V)
    return d;
}

namespace {

class ItnGauge final : public Gauge {
  public:
    ItnGauge(std::unique_ptr<ItnLink> link, bool inch) : link_(std::move(link)), inch_(inch) {
        using namespace std::chrono_literals;
        link_->control_out(kItnRequestInit, kItnInitValue, {}, 500ms);
        std::array<std::uint8_t, 1> status{};
        if (link_->control_in(kItnRequestStatus, 0, status, 500ms) != 1)
            throw DeviceError(DeviceErrorKind::Protocol, link_->uri() + ": no status byte after the init request");
    }

    Identity identify() override {
        Identity id;
        id.kind = Kind::MitutoyoItn;
        id.maker = "Mitutoyo";
        id.serial = link_->serial();
        id.model = link_->product().empty() ? "USB-ITN" : link_->product();
        const Decoded v = ask("V\r", std::chrono::milliseconds(1000));
        id.firmware = v.text;
        id.inch = inch_;
        return id;
    }

    Reading read(std::chrono::milliseconds timeout) override {
        Decoded d = ask("1\r", timeout);
        d.reading.inch = inch_;  // the line has no unit: the URI says which the gauge is set to
        if (d.reading.status == ReadingStatus::Error && d.reading.code == 0)
            throw DeviceError(DeviceErrorKind::Protocol, uri() + ": '1' answered '" + d.text + "'");
        return d.reading;
    }

    std::string uri() const override { return link_->uri(); }

  private:
    Decoded ask(std::string_view command, std::chrono::milliseconds timeout) {
        using clock = std::chrono::steady_clock;
        std::array<std::uint8_t, 64> buf{};
        while (link_->interrupt_in(buf, std::chrono::milliseconds(1)) > 0) {  // a late or cut-off reply
        }
        rx_.clear();
        link_->control_out(kItnRequestCommand, 0,
                           {reinterpret_cast<const std::uint8_t*>(command.data()), command.size()}, timeout);
        const auto deadline = clock::now() + timeout;
        for (;;) {
            const Decoded d = decode_itn(rx_);
            if (d.result == Decode::Valid) return d;
            if (d.result == Decode::Invalid)
                throw DeviceError(DeviceErrorKind::Protocol,
                                  uri() + ": reply outside the protocol: '" + rx_.substr(0, d.consumed) + "'");
            const auto now = clock::now();
            if (now >= deadline)
                throw DeviceError(DeviceErrorKind::Timeout,
                                  uri() + (rx_.empty() ? ": no reply" : ": reply cut off ('" + rx_ + "')"));
            const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now);
            const std::size_t n = link_->interrupt_in(buf, std::max(left, std::chrono::milliseconds(1)));
            for (std::size_t i = 0; i < n; ++i)
                if (buf[i] != 0) rx_.push_back(static_cast<char>(buf[i]));  // reports are zero-padded
        }
    }

    std::unique_ptr<ItnLink> link_;
    bool inch_;
    std::string rx_;
};

}  // namespace

std::unique_ptr<Gauge> make_itn_gauge(std::unique_ptr<ItnLink> link, bool inch) {
    return std::make_unique<ItnGauge>(std::move(link), inch);
}

}  // namespace ballbar::device::gauge
