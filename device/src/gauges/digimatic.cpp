// SPDX-License-Identifier: MIT
// Mitutoyo Digimatic gauges through a USB CDC adaptor: any character asks for one reading; the adaptor
// clocks the gauge's 52-bit SPC frame in and answers with one decimal line, or `#` and an error
// (docs/instruments.md, "Digimatic").
#include <memory>

#include "ballbar/device/gauge.hpp"
#include "line_link.hpp"

namespace ballbar::device::gauge {

Decoded decode_digimatic_line(std::string_view rx) {
    Decoded d = detail::take_line(rx, '\n');
    if (d.result != Decode::Valid) return d;
    if (!d.text.empty() && d.text[0] == '#') {
        const std::string_view what = std::string_view(d.text).substr(1);
        d.reading.status = what == "NR"   ? ReadingStatus::NotReady
                           : what == "OR" ? ReadingStatus::OutOfRange
                                          : ReadingStatus::Error;
        return d;
    }
    std::string_view num = d.text;
    bool inch = false;
    if (num.size() > 3 && num.substr(num.size() - 3) == " in") {
        inch = true;
        num.remove_suffix(3);
    } else if (num.size() > 3 && num.substr(num.size() - 3) == " mm") {
        num.remove_suffix(3);
    }
    if (auto r = parse_decimal(num)) {
        d.reading = *r;
        d.reading.inch = inch;
        return d;
    }
    d.result = Decode::Invalid;
    return d;
}

Decoded decode_spc_frame(std::span<const std::uint8_t> n) {
    Decoded d;
    if (n.size() < 13) return d;
    d.consumed = 13;
    d.result = Decode::Invalid;
    for (int i = 0; i < 4; ++i)
        if (n[static_cast<std::size_t>(i)] != 0xF) return d;
    if (n[4] != 0 && n[4] != 8) return d;
    double v = 0;
    for (std::size_t i = 5; i <= 10; ++i) {
        if (n[i] > 9) return d;
        v = v * 10 + n[i];
    }
    if (n[11] > 5 || n[12] > 1) return d;
    d.result = Decode::Valid;
    d.reading.decimals = n[11];
    d.reading.inch = n[12] == 1;
    for (int i = 0; i < d.reading.decimals; ++i) v /= 10;
    d.reading.value = n[4] == 8 ? -v : v;
    return d;
}

namespace {

class DigimaticGauge final : public Gauge {
  public:
    explicit DigimaticGauge(std::unique_ptr<Transport> link) : link_(std::move(link)) {}

    Identity identify() override {
        Identity id;
        id.kind = Kind::Digimatic;
        id.maker = "Mitutoyo";
        id.model = "Digimatic gauge (USB CDC adaptor)";
        // The frame carries the unit: one reading tells it (and that the adaptor answers at all).
        const Decoded d = detail::ask(*link_, rx_, "R", decode_digimatic_line, std::chrono::milliseconds(1000));
        id.inch = d.reading.inch;
        return id;
    }

    Reading read(std::chrono::milliseconds timeout) override {
        return detail::ask(*link_, rx_, "R", decode_digimatic_line, timeout).reading;
    }

    std::string uri() const override { return "digimatic:" + link_->uri().substr(link_->uri().find(':') + 1); }

  private:
    std::unique_ptr<Transport> link_;
    std::string rx_;
};

}  // namespace

std::unique_ptr<Gauge> make_digimatic_gauge(std::unique_ptr<Transport> link) {
    return std::make_unique<DigimaticGauge>(std::move(link));
}

}  // namespace ballbar::device::gauge
