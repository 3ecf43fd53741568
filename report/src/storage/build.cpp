// SPDX-License-Identifier: MIT
// build_report: one pass over the session's samples (bar-reading figure, bar temperatures, capture
// window times), then points, audit trail and stored results.
#include "ballbar/report/build.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "../circular.hpp"
#include "ballbar/analysis/circular.hpp"
#include "ballbar/analysis/rounding.hpp"
#include "ballbar/report/decimate.hpp"
#include "ballbar/report/results.hpp"
#include "ballbar/storage/circular_result.hpp"
#include "ballbar/storage/identification_codec.hpp"
#include "ballbar/storage/session_clock.hpp"
#include "ballbar/storage/trace_file.hpp"

namespace ballbar::report {

namespace {

double parse_iso8601(const std::string& s) {
    return storage::iso8601_seconds(s);
}

void add_temperature(Range& r, double v, double& sum, std::size_t& n) {
    if (!std::isfinite(v)) return;
    r.min = std::min(r.min.value_or(v), v);
    r.max = std::max(r.max.value_or(v), v);
    sum += v;
    ++n;
    r.mean = analysis::decimal_round(sum / static_cast<double>(n), 4);  // 0.1 mK: no float noise
}

std::string procedure_kind(const storage::Transition& t) {
    using storage::SessionState;
    if (t.to == SessionState::interrupted) return "pause";
    if (t.from == SessionState::interrupted && t.to == SessionState::running) return "resume";
    if (t.to == SessionState::aborted) return "abort";
    if (t.to == SessionState::failed) return "fail";
    if (t.to == SessionState::completed) return "finish";
    return "step";
}

constexpr std::size_t kPolarColumns = 720;  ///< angle columns of each run's polar plot (≤ 4 points each)

/// The circular test of a session of procedure "circular": its stored result (the latest), else the
/// analysis made now; the runs' polar plots from the stored samples; the trace's temperatures.
void add_circular_test(Report& r, storage::Store& store, std::int64_t session_id,
                       const std::optional<storage::ResultRecord>& stored) {
    storage::TraceFile trace;
    try {
        trace = storage::load_trace(store, session_id);
    } catch (const storage::StorageError&) {
        throw;
    } catch (const std::exception& e) {
        r.circular_note = std::string("the circular test cannot be read: ") + e.what();
        return;
    }
    if (stored && r.circular) {
        r.circular->source = "stored result " + std::to_string(stored->id) + " (" + stored->created_at + ")";
    } else {
        try {
            const auto result = analysis::circular::analyze_circular(trace.test, trace.samples);
            add_result(r, "circular",
                       nlohmann::json::parse(storage::circular_result_json(result, trace, std::nullopt)));
            r.circular->source = "analysed for this report (no stored result)";
        } catch (const analysis::circular::CircularError& e) {
            r.circular_note = std::string("the circular test cannot be analysed: ") + e.what();
            return;
        }
    }
    CircularTest& c = *r.circular;
    // Temperatures as the trace holds them (a trace without a bar temperature column has none).
    auto range = [](const std::vector<std::optional<double>>& v) {
        Range out;
        double sum = 0;
        std::size_t n = 0;
        for (const auto& x : v)
            if (x && std::isfinite(*x))
                out.min = std::min(out.min.value_or(*x), *x), out.max = std::max(out.max.value_or(*x), *x), sum += *x,
                ++n;
        if (n > 0) out.mean = analysis::decimal_round(sum / static_cast<double>(n), 4);  // 0.1 mK
        return out;
    };
    c.bar_temp_C = range(trace.bar_temp_C);
    c.air_temp_C = range(trace.air_temp_C);
    r.header.bar_temp_C = c.bar_temp_C;
    r.header.air_temp_C = c.air_temp_C;
    if (c.instrument.empty()) c.instrument = trace.instrument_json;
    std::vector<CircularSample> samples;
    samples.reserve(trace.samples.size());
    for (const auto& s : trace.samples) samples.push_back({s.time_s, s.measured_mm});
    circular_polar(c, samples, kPolarColumns);
}

}  // namespace

Report build_report(storage::Store& store, std::int64_t session_id, const BuildOptions& options) {
    const storage::SessionInfo info = store.session(session_id);
    Report r;
    Header& h = r.header;
    h.session_id = info.id;
    h.session_name = info.procedure.empty() ? info.uuid.substr(0, 8) : info.procedure + " " + info.uuid.substr(0, 8);
    h.status = std::string(storage::to_string(info.state));
    h.started_at = info.started_at;
    h.finished_at = info.ended_at.value_or("");
    h.machine = info.machine;
    if (info.instrument) {
        h.instrument_model = info.instrument->model;
        h.instrument_serial = info.instrument->serial;
        h.instrument_firmware = info.instrument->firmware;
        h.instrument_calibration_date = info.instrument->calibration_date;
        h.calibrated_length_mm = info.instrument->calibrated_length_mm;
    }
    h.operator_name = info.operator_name;
    h.notes = info.notes;
    h.software_version = options.software_version;
    const double t0_wall = parse_iso8601(info.started_at);

    // Points: the capture windows need the times of their first and last samples.
    const std::vector<storage::PointRecord> points = store.points(session_id);
    std::vector<std::uint64_t> wanted;
    for (const auto& p : points) {
        if (p.first_seq) wanted.push_back(*p.first_seq);
        if (p.last_seq) wanted.push_back(*p.last_seq);
    }
    std::sort(wanted.begin(), wanted.end());
    wanted.erase(std::unique(wanted.begin(), wanted.end()), wanted.end());
    std::vector<double> wanted_time(wanted.size(), std::nan(""));

    // Samples, in one pass: the time span comes from the first and the last sample.
    const std::uint64_t count = store.next_seq(session_id);
    double sum_bar = 0, sum_machine = 0, sum_air = 0;
    std::size_t n_bar = 0, n_machine = 0, n_air = 0;
    if (count > 0) {
        // One monotonic session time across reconnects and resumes (the device clock restarts).
        const storage::SessionClock clock(store, session_id);
        {
            const double t_first = clock.first_s(), t_last = clock.last_s();
            MinMaxDecimator dec(t_first, std::max(t_last, t_first + 1e-6),
                                std::max<std::size_t>(1, options.trace_columns));
            double lo = std::numeric_limits<double>::infinity(), hi = -lo;
            std::size_t next_wanted = 0;
            store.for_each_sample(session_id, [&](const analysis::BarSample& s) {
                const double t = clock.seconds(s.seq, s.device_time_us);
                const double um = s.displacement_nm * 1e-3;
                dec.add(t, um);
                lo = std::min(lo, um);
                hi = std::max(hi, um);
                if (!(s.flags & analysis::kSampleTempInvalid))
                    add_temperature(h.bar_temp_C, s.temperature_C(), sum_bar, n_bar);
                while (next_wanted < wanted.size() && wanted[next_wanted] < s.seq) ++next_wanted;
                if (next_wanted < wanted.size() && wanted[next_wanted] == s.seq) wanted_time[next_wanted++] = t;
            });
            r.trace.samples = dec.seen();
            XYSeries kept = dec.take();
            r.trace.time_s = std::move(kept.x);
            for (double& t : r.trace.time_s) t = analysis::decimal_round(t, 6);  // the instrument's µs clock
            r.trace.displacement_um = std::move(kept.y);
            if (r.trace.samples > 0) r.trace.min_um = lo, r.trace.max_um = hi;
        }
        for (const auto& g : store.sample_gaps(session_id)) {
            ++r.trace.gaps;
            r.trace.gap_s += g.duration_s.value_or(0);
        }
    }
    auto time_of = [&](std::uint64_t seq) {
        const auto it = std::lower_bound(wanted.begin(), wanted.end(), seq);
        return it != wanted.end() && *it == seq ? wanted_time[static_cast<std::size_t>(it - wanted.begin())]
                                                : std::nan("");
    };
    for (const auto& p : points) {
        const auto& rd = p.reading;
        if (n_bar == 0 && rd.bar_temp_C) add_temperature(h.bar_temp_C, *rd.bar_temp_C, sum_bar, n_bar);
        if (rd.machine_temp_C) add_temperature(h.machine_temp_C, *rd.machine_temp_C, sum_machine, n_machine);
        if (rd.air_temp_C) add_temperature(h.air_temp_C, *rd.air_temp_C, sum_air, n_air);
        CaptureWindow c;
        c.location = rd.location;
        c.point = rd.point;
        c.mean_um = (rd.measured_mm - p.nominal_mm) * 1000.0;
        if (p.first_seq && p.last_seq) {
            c.start_s = analysis::decimal_round(time_of(*p.first_seq), 6);
            c.end_s = analysis::decimal_round(time_of(*p.last_seq), 6);
        }
        if (!std::isfinite(c.start_s) || !std::isfinite(c.end_s)) {  // imported readings: no samples behind them
            const double half = rd.n > 0 ? rd.n * 5e-4 : 0.25;
            c.start_s = rd.time_s - half;
            c.end_s = rd.time_s + half;
        }
        r.captures.push_back(c);
    }

    // The audit trail of the session, then the stored results in the order they were added.
    for (const auto& t : store.transitions(session_id)) {
        ProcedureEvent e;
        e.timestamp = t.at;
        const double wall = parse_iso8601(t.at);
        e.time_s = std::isfinite(wall) && std::isfinite(t0_wall) ? analysis::decimal_round(wall - t0_wall, 3)
                                                                 : 0;  // ms stamps
        e.kind = procedure_kind(t);
        e.step = std::string(storage::to_string(t.to));
        e.detail = t.event;
        r.procedure.push_back(e);
    }
    // The guided procedure's steps, through the same reading as an "acquisition.transition" result
    // (how schema v1 stored them, and how a report JSON carries them).
    for (const auto& step : store.procedure_steps(session_id)) {
        const double wall = parse_iso8601(step.at);
        const nlohmann::json payload = {
            {"from", step.from},
            {"to", step.to},
            {"event", step.event},
            {"detail", step.detail},
            {"at", step.at},
            {"time_s",
             std::isfinite(wall) && std::isfinite(t0_wall) ? analysis::decimal_round(wall - t0_wall, 3) : 0.0}};
        add_result(r, "acquisition.transition", payload);
    }
    std::optional<storage::ResultRecord> circular_result;
    for (const auto& res : store.results(session_id)) {
        if (res.kind == "circular") circular_result = res;
        nlohmann::json payload;
        try {
            payload = nlohmann::json::parse(res.payload_json);
        } catch (const nlohmann::json::exception& e) {  // parse_error, and out_of_range for a number past double
            throw ReportError("result " + std::to_string(res.id) + " (" + res.kind +
                              "): payload is not JSON: " + e.what());
        }
        if (res.kind == "acquisition.transition" && payload.is_object()) {  // a v1 file read as it is
            payload["at"] = res.created_at;
            const double wall = parse_iso8601(res.created_at);
            payload["time_s"] =
                std::isfinite(wall) && std::isfinite(t0_wall) ? analysis::decimal_round(wall - t0_wall, 3) : 0.0;
        }
        try {
            add_result(r, res.kind, payload);
        } catch (const ReportError& e) {
            throw ReportError("result " + std::to_string(res.id) + ": " + e.what());
        }
        if (res.kind == storage::kIdentificationResultKind && r.model && res.model_id) {
            const storage::ModelRecord m = store.model(*res.model_id);  // the model version it produced
            r.model->name = m.name + " v" + std::to_string(m.version);
        }
    }
    if (info.procedure == "circular") add_circular_test(r, store, session_id, circular_result);
    // The commanded angle of an orientation error: the axis's angle at the points after the rotation.
    for (auto& o : r.orientation) {
        if (o.commanded_rad || o.to_location < 0) continue;
        for (const auto& p : points) {
            if (p.reading.location != o.to_location) continue;
            const auto& pose = p.reading.pose;
            o.commanded_rad = o.axis == "A" ? pose.A_rad : o.axis == "B" ? pose.B_rad : pose.C_rad;
            break;
        }
    }
    std::stable_sort(r.procedure.begin(), r.procedure.end(),
                     [](const ProcedureEvent& a, const ProcedureEvent& b) { return a.time_s < b.time_s; });
    std::stable_sort(r.locations.begin(), r.locations.end(),
                     [](const LocationError& a, const LocationError& b) { return a.location < b.location; });
    return r;
}

}  // namespace ballbar::report
