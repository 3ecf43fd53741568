// SPDX-License-Identifier: MIT
// Sylvac indicators on their serial cable: 4800 baud, 7 data bits, even parity, 2 stop bits; commands
// and replies end with CR (docs/instruments.md, "Sylvac").
#include <memory>

#include "ballbar/device/gauge.hpp"
#include "line_link.hpp"

namespace ballbar::device::gauge {

Decoded decode_sylvac(std::string_view rx) {
    Decoded d = detail::take_line(rx, '\r');
    if (d.result != Decode::Valid) return d;
    if (auto r = parse_decimal(d.text)) {
        d.reading = *r;
        return d;
    }
    if (d.text.size() >= 2 && d.text[0] == 'E') {
        if (auto code = parse_decimal(d.text.substr(1)); code && code->decimals == 0 && code->value >= 0) {
            // Up to 12 digits parse; a code past int is no code we know (found by fuzz_gauge_replies: the
            // conversion was undefined).
            d.reading.code = code->value < 1e9 ? static_cast<int>(code->value) : 999'999'999;
            d.reading.status = d.reading.code == 1   ? ReadingStatus::NotReady
                               : d.reading.code == 2 ? ReadingStatus::OutOfRange
                                                     : ReadingStatus::Error;
            return d;
        }
    }
    if (d.text.empty()) {
        d.result = Decode::Invalid;
        return d;
    }
    d.reading.status = ReadingStatus::Error;  // not a reading: an answer in `text`
    return d;
}

namespace {

class SylvacGauge final : public Gauge {
  public:
    explicit SylvacGauge(std::unique_ptr<Transport> link) : link_(std::move(link)) {}

    Identity identify() override {
        using namespace std::chrono_literals;
        Identity id;
        id.kind = Kind::Sylvac;
        id.maker = "Sylvac";
        id.model = "indicator";
        const Decoded unit = detail::ask(*link_, rx_, "UNI?\r", decode_sylvac, 1000ms);
        if (unit.text == "IN" || unit.text == "INCH") {
            id.inch = true;
        } else if (unit.text != "MM") {
            throw DeviceError(DeviceErrorKind::Protocol, uri() + ": UNI? answered '" + unit.text + "'");
        }
        inch_ = id.inch;
        const Decoded bat = detail::ask(*link_, rx_, "BAT?\r", decode_sylvac, 1000ms);
        if (bat.text != "BAT1" && bat.text != "BAT0")
            throw DeviceError(DeviceErrorKind::Protocol, uri() + ": BAT? answered '" + bat.text + "'");
        id.low_battery = bat.text == "BAT0";
        return id;
    }

    Reading read(std::chrono::milliseconds timeout) override {
        Decoded d = detail::ask(*link_, rx_, "?\r", decode_sylvac, timeout);
        if (d.reading.status == ReadingStatus::Error && d.reading.code == 0)
            throw DeviceError(DeviceErrorKind::Protocol, uri() + ": '?' answered '" + d.text + "'");
        d.reading.inch = inch_;
        return d.reading;
    }

    std::string uri() const override { return "sylvac:" + link_->uri().substr(link_->uri().find(':') + 1); }

  private:
    std::unique_ptr<Transport> link_;
    std::string rx_;
    bool inch_ = false;
};

}  // namespace

std::unique_ptr<Gauge> make_sylvac_gauge(std::unique_ptr<Transport> link) {
    return std::make_unique<SylvacGauge>(std::move(link));
}

}  // namespace ballbar::device::gauge
