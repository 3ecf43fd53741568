// SPDX-License-Identifier: MIT
// Digital gauges a low-cost ball-bar is built on (docs/instruments.md): Sylvac indicators on their serial
// cable, Mitutoyo gauges on a USB-ITN cable (libusb), Mitutoyo Digimatic gauges behind a USB CDC adaptor,
// and Modbus RTU indicators (libmodbus). Each protocol has a pure codec (bytes in; valid / invalid /
// need more out, as libsigrok's parsers answer) and a driver over a link; a GaugeSampler polls a driver at
// its rate and turns each reading into a BarSample (bar length = calibrated length + sign × displacement
// from the zero set in the calibrator).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "ballbar/analysis/sample.hpp"
#include "ballbar/device/transport.hpp"

namespace ballbar::device::gauge {

enum class Kind { Sylvac, MitutoyoItn, Digimatic, Modbus };
/// The URI scheme and `--instrument` name: "sylvac", "mitutoyo-itn", "digimatic", "modbus".
const char* to_string(Kind kind);
std::optional<Kind> parse_kind(std::string_view name);

// ---- codecs ---------------------------------------------------------------------------------------

enum class Decode { NeedMore, Valid, Invalid };

enum class ReadingStatus {
    Ok,          ///< a value
    NotReady,    ///< the gauge answered but has no value yet (`918`, `#…`, Modbus busy, `E1`)
    OutOfRange,  ///< the spindle is beyond the gauge's range
    Error,       ///< another status or error code from the gauge or its cable
};
const char* to_string(ReadingStatus s);

struct Reading {
    ReadingStatus status = ReadingStatus::Ok;
    double value = 0;   ///< in the gauge's unit (mm, or inch when `inch`)
    bool inch = false;  ///< the value is in inches
    int decimals = 0;   ///< digits after the decimal point as sent: the resolution is 10^-decimals unit
    int code = 0;       ///< the gauge's status or error code when not Ok
    double value_mm() const { return inch ? value * 25.4 : value; }
    double resolution_mm() const;
};

/// What a codec made of the front of a byte buffer. `consumed` bytes may be dropped (also when Invalid:
/// the bad line, so the next one can be decoded); NeedMore consumes nothing.
struct Decoded {
    Decode result = Decode::NeedMore;
    std::size_t consumed = 0;
    Reading reading;
    std::string text;  ///< the line without its terminator (answers that are not readings: `MM`, `BAT0`, …)
};

/// Longest line any of the ASCII protocols sends; more without a terminator is Invalid.
inline constexpr std::size_t kMaxLine = 40;

/// A signed decimal number "+001.234", "-0.0520", "12": the reading (status Ok, decimals counted).
std::optional<Reading> parse_decimal(std::string_view text);

/// Sylvac: one CR-terminated reply line. A number is a reading; `E<n>` an error (1 not ready,
/// 2 out of range); anything else printable is Valid with an Error status and the line in `text`
/// (answers to `UNI?`, `BAT?`, … are read from `text`).
Decoded decode_sylvac(std::string_view rx);

/// Mitutoyo USB-ITN: one CR-terminated line from the interrupt endpoint: `01A+0000.123` (code "0",
/// channel "1", item "A", sign, eight characters with the decimal point) is a reading; `9…` a status
/// (918: not ready; 911: out of range); anything else printable is Valid with the line in `text` (`V` answer).
Decoded decode_itn(std::string_view rx);

/// Digimatic USB CDC adaptor: one LF-terminated line (a CR before the LF is dropped): a decimal number,
/// or `#` and an error text (`#NR` the gauge did not answer: not ready; `#OR` out of range; other: Error).
Decoded decode_digimatic_line(std::string_view rx);

/// The Digimatic SPC frame: 13 nibbles d1..d13 (d1–d4 0xF, d5 sign 0/8, d6–d11 six BCD digits most
/// significant first, d12 decimal point position 0–5, d13 unit 0 mm / 1 inch). Invalid for anything else.
Decoded decode_spc_frame(std::span<const std::uint8_t> nibbles);

/// Modbus RTU indicator: registers 0x0000 (high word) and 0x0001 (low word), signed 32-bit, mm × 10⁴.
Reading modbus_reading(std::uint16_t high, std::uint16_t low);

// ---- drivers --------------------------------------------------------------------------------------

struct Identity {
    Kind kind = Kind::Sylvac;
    std::string maker, model, serial, firmware;  ///< empty where the gauge does not tell
    bool inch = false;                           ///< the gauge reports inches
    bool low_battery = false;
};

/// One gauge on its link. read() asks for one reading and waits for it; it throws DeviceError: Timeout
/// (no reply, or a reply cut off), Protocol (a reply outside the grammar), Disconnected, Io.
class Gauge {
  public:
    virtual ~Gauge() = default;
    virtual Identity identify() = 0;
    virtual Reading read(std::chrono::milliseconds timeout) = 0;
    virtual std::string uri() const = 0;
};

/// True for the gauge URI schemes: sylvac:, mitutoyo-itn:, digimatic:, modbus:.
bool is_gauge_uri(std::string_view uri);
Kind uri_kind(std::string_view uri);

/// Opens `sylvac:PATH`, `mitutoyo-itn:[SERIAL]`, `digimatic:PATH` or `modbus:PATH[?slave=N&baud=B]`.
/// Every scheme also takes the bar's parameters `sign=1|-1` and `rate=R` (bar_from_uri) and
/// `unit=mm|inch` (for protocols whose replies carry no unit: mitutoyo-itn).
/// Throws std::invalid_argument (malformed URI) or DeviceError.
std::unique_ptr<Gauge> open_gauge(std::string_view uri);

/// The serial gauge (digimatic, sylvac, modbus, tried in that order) that answers one reading on the
/// serial port at `path` within `per_protocol` each; none when nothing does. For a port the ball-bar
/// protocol found silent: what the operator probably meant.
std::optional<Kind> find_serial_gauge(const std::string& path, std::chrono::milliseconds per_protocol);
/// For a `serial:PATH` URI whose instrument did not answer: "; a sylvac gauge answers on PATH: use
/// --device sylvac:PATH" when one does (find_serial_gauge: two requests of 250 ms per protocol, 1.5 s at most), else
/// "".
std::string serial_gauge_hint(std::string_view uri);
inline constexpr std::string_view kUseDevice = ": use --device ";
/// The device a serial_gauge_hint in `message` names ("sylvac:/dev/ttyUSB0"), wherever in the message it
/// stands; none without one. For the resume line of a session stopped by it: the device that answers.
std::optional<std::string> hinted_device(std::string_view message);

std::unique_ptr<Gauge> make_sylvac_gauge(std::unique_ptr<Transport> link);
std::unique_ptr<Gauge> make_digimatic_gauge(std::unique_ptr<Transport> link);
std::unique_ptr<Gauge> open_modbus_gauge(const std::string& path, int slave, int baud);

/// The USB-ITN's USB side: vendor control transfers out/in and its interrupt-IN endpoint.
class ItnLink {
  public:
    virtual ~ItnLink() = default;
    /// bmRequestType 0x40 (vendor, host to device).
    virtual void control_out(std::uint8_t request, std::uint16_t value, std::span<const std::uint8_t> data,
                             std::chrono::milliseconds timeout) = 0;
    /// bmRequestType 0xC0 (vendor, device to host); returns the bytes read.
    virtual std::size_t control_in(std::uint8_t request, std::uint16_t value, std::span<std::uint8_t> data,
                                   std::chrono::milliseconds timeout) = 0;
    /// One interrupt-IN transfer; 0 on timeout.
    virtual std::size_t interrupt_in(std::span<std::uint8_t> data, std::chrono::milliseconds timeout) = 0;
    virtual std::string serial() const = 0;
    virtual std::string product() const = 0;
    virtual std::string uri() const = 0;
};

inline constexpr std::uint16_t kItnVendorId = 0x0FE7;
inline constexpr std::uint16_t kItnProductId = 0x4001;
inline constexpr std::uint8_t kItnRequestInit = 0x01;  ///< 0x40, wValue 0xA5A5
inline constexpr std::uint16_t kItnInitValue = 0xA5A5;
inline constexpr std::uint8_t kItnRequestStatus = 0x02;   ///< 0xC0, one byte
inline constexpr std::uint8_t kItnRequestCommand = 0x03;  ///< 0x40, ASCII + CR
inline constexpr std::uint8_t kItnInterruptEndpoint = 0x81;

/// Opens the first USB-ITN (whose serial-number string is `serial` unless empty) through libusb.
std::unique_ptr<ItnLink> open_itn_usb(const std::string& serial);
/// `inch`: the gauge is set to inches (the ITN's data line does not say).
std::unique_ptr<Gauge> make_itn_gauge(std::unique_ptr<ItnLink> link, bool inch = false);

// ---- a bar built on a gauge -----------------------------------------------------------------------

struct BarOnGauge {
    double calibrated_length_mm = 150;  ///< the bar's length when the gauge reads its zero
    double sign = +1;                   ///< +1: the gauge reading grows with the bar; -1: it shrinks
    double target_rate_hz = 20;         ///< how often to ask for a reading (the gauge may be slower)
};

struct SamplerStats {
    std::uint64_t readings = 0;  ///< values received
    std::uint64_t not_ready = 0, out_of_range = 0, errors = 0, timeouts = 0, invalid = 0;
    double resolution_mm = 0;  ///< finest step the gauge's readings carry (from the digits it sends)
    double rate_hz = 0;        ///< actual readings per second, over the last readings
};

/// `bar` with the URI's `sign=` and `rate=` applied (std::invalid_argument when malformed).
BarOnGauge bar_from_uri(std::string_view uri, BarOnGauge bar);

/// Polls a gauge at (at most) the target rate: each reading becomes a BarSample whose displacement is
/// sign × (reading − zero) and whose time is the injected clock's. A reading that fails (not ready, out of
/// range, no reply, cut off, invalid) produces no sample and marks the next with kSampleAfterGap.
class GaugeSampler {
  public:
    using Clock = std::function<std::uint64_t()>;  ///< µs
    GaugeSampler(std::unique_ptr<Gauge> gauge, BarOnGauge bar, Clock clock = {});

    const Identity& identify();
    /// Zero: the mean of `n` good readings (the bar in its calibrator).
    void set_zero(int n = 5);
    bool zeroed() const { return zero_mm_.has_value(); }
    std::optional<double> zero_mm() const { return zero_mm_; }
    /// A zero found before (a reconnected gauge keeps its mechanical origin).
    void set_zero_value(double mm) { zero_mm_ = mm; }
    /// Waits for the next due time, asks for one reading; a sample when it gave a value.
    std::optional<analysis::BarSample> poll(std::chrono::milliseconds timeout);
    /// Measures the reading rate and resolution from `n` readings (no samples made).
    void measure(int n);

    const SamplerStats& stats() const { return stats_; }
    Gauge& gauge() { return *gauge_; }
    const BarOnGauge& bar() const { return bar_; }

  private:
    std::optional<Reading> read_one(std::chrono::milliseconds timeout);
    void note_time(std::uint64_t t_us);

    std::unique_ptr<Gauge> gauge_;
    BarOnGauge bar_;
    Clock clock_;
    std::optional<Identity> identity_;
    std::optional<double> zero_mm_;
    SamplerStats stats_;
    bool gap_ = false;
    bool real_time_ = false;  ///< no clock was injected: pace with the steady clock
    std::uint64_t next_due_us_ = 0;
    std::uint64_t rate_t0_us_ = 0, rate_n_ = 0;
};

/// `mm` rounded to nanometres, saturating at ±2.1 m.
std::int32_t to_nm(double mm);

/// Circular tests on a slow gauge: the highest feed (mm/min) at which a circle of `radius_mm` still gets
/// `min_samples_per_deg` readings per degree of arc at `rate_hz` readings per second.
double max_feed_for_rate(double rate_hz, double radius_mm, double min_samples_per_deg = 1.0);

}  // namespace ballbar::device::gauge
