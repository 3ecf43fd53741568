// SPDX-License-Identifier: MIT
#include "ballbar/workflow/circular_measure.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>

#include "ballbar/storage/circular_result.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/gauge_source.hpp"
#include "ballbar/workflow/session_io.hpp"

namespace ballbar::workflow {

namespace acq = ballbar::acquisition;
namespace circ = ballbar::analysis::circular;
using ojson = nlohmann::ordered_json;

// ---- the sink -------------------------------------------------------------------------------------------

CircularStoreSink::CircularStoreSink(storage::Store& store, Create create, double reference_length_mm)
    : store_(store), create_(std::move(create)), reference_mm_(reference_length_mm) {}

CircularStoreSink::CircularStoreSink(storage::Store& store, std::int64_t id, double reference_length_mm)
    : store_(store), id_(id), reference_mm_(reference_length_mm) {
    writer_.emplace(store_, id);
}

void CircularStoreSink::identified(const device::InstrumentInfo& info) {
    reference_mm_ = info.calibrated_length_mm;
    const storage::Instrument inst = stored_instrument(info);
    instrument_ = inst;
    if (id_) store_.set_instrument(*id_, inst);
}

void CircularStoreSink::on_transition(const acq::TransitionRecord& t) {
    const storage::ProcedureStep step{std::string(acq::to_string(t.from)), std::string(acq::to_string(t.to)),
                                      std::string(acq::to_string(t.event)), t.detail, store_.now_iso8601()};
    if (id_)
        store_.add_procedure_step(*id_, step);
    else
        pending_.push_back(step);
}

void CircularStoreSink::on_samples(std::span<const analysis::BarSample> samples) {
    ensure();
    for (const auto& s : samples) {
        const std::uint64_t stored = writer_->append(s);
        if (runs_.empty() || s.seq != last_source_ + 1 || stored != last_stored_ + 1) runs_.push_back({s.seq, stored});
        last_source_ = s.seq;
        last_stored_ = stored;
    }
}

void CircularStoreSink::on_attempt(const acq::CircularAttempt& a) {
    ensure();
    writer_->flush();
    ojson runs = ojson::array();
    for (const auto& r : a.runs)
        runs.push_back({{"direction", circ::direction_name(r.direction)},
                        {"feed_in_end_s", r.feed_in_end_s},
                        {"servo_lag_ms", r.lag_s * 1e3},
                        {"first_seq", stored(r.first_seq)},
                        {"last_seq", stored(r.last_seq)}});
    const ojson j = {{"attempt", a.attempt},
                     {"good", a.good},
                     {"why", a.why.empty() ? ojson(nullptr) : ojson(a.why)},
                     {"reference_length_mm", reference_mm_},
                     {"first_seq", stored(a.first_seq)},
                     {"last_seq", stored(a.last_seq)},
                     {"runs", runs}};
    store_.add_result(*id_, "circular.attempt", j.dump(), std::nullopt, "ballbar circle measure/1");
}

void CircularStoreSink::finish(const acq::CircularSummary& sum) {
    if (!id_) return;  // refused before a session was made: nothing to store
    writer_->flush();
    const std::int64_t id = *id_;
    if (sum.interrupted) {
        store_.transition(id, storage::SessionState::interrupted, "interrupted: " + sum.reason);
    } else if (sum.final_state == acq::State::Done) {
        store_.finish_session(id);
    } else if (sum.final_state == acq::State::Aborted) {
        store_.abort_session(id, sum.reason.empty() ? "abort" : "abort: " + sum.reason);
    } else {
        store_.fail_session(id, "fail: " + sum.reason);
    }
}

void CircularStoreSink::ensure() {
    if (id_) return;
    id_ = create_();
    writer_.emplace(store_, *id_);
    if (instrument_) store_.set_instrument(*id_, *instrument_);
    for (const auto& step : pending_) store_.add_procedure_step(*id_, step);
    pending_.clear();
}

std::int64_t CircularStoreSink::stored(std::uint64_t source_seq) const {
    auto it = std::upper_bound(runs_.begin(), runs_.end(), source_seq,
                               [](std::uint64_t q, const SeqRun& r) { return q < r.source; });
    if (it == runs_.begin()) return -1;
    --it;
    return static_cast<std::int64_t>(it->stored + (source_seq - it->source));
}

// ---- sessions -------------------------------------------------------------------------------------------

std::int64_t create_circular_session(storage::Store& store, const circ::TestSpec& test, analysis::NcDialect dialect,
                                     double dwell_s, storage::SessionSource source, const std::string& operator_name,
                                     const std::string& notes, const analysis::MachineGeometry* machine,
                                     std::optional<double> tolerance_um, const std::string& machine_asset) {
    storage::NewSession ns;
    ns.machine_asset = machine_asset;
    if (machine)
        ns.machine = *machine;
    else
        ns.machine.name = "circular test";
    ns.source = source;
    ns.operator_name = operator_name;
    ns.procedure = "circular";
    ns.notes = notes;
    ojson meta = {{"format", "ballbar-trace/1"},
                  {"test", ojson::parse(storage::test_json(test))},
                  {"reference_length_mm", test.radius_mm},
                  {"has_bar_temp", true},
                  {"part_program", {{"dialect", analysis::to_string(dialect)}, {"dwell_s", dwell_s}}},
                  {"extra", ojson::object()}};
    if (tolerance_um) meta["tolerance_um"] = *tolerance_um;
    ns.metadata_json = meta.dump();
    const std::int64_t id = store.create_session(ns);
    store.start_session(id);
    return id;
}

StoredCircularResult analyze_stored_circular(storage::Store& store, std::int64_t id) {
    StoredCircularResult out;
    out.trace = storage::load_trace(store, id);
    try {
        out.result = circ::analyze_circular(out.trace.test, out.trace.samples);
    } catch (const circ::CircularError& e) {
        throw Error(ErrorCategory::failed, "session " + std::to_string(id) + ": the stored trace: " + e.what());
    }
    std::optional<double> tolerance_um;
    const ojson meta = ojson::parse(store.session(id).metadata_json, nullptr, false);
    if (meta.is_object() && meta.contains("tolerance_um") && meta["tolerance_um"].is_number() &&
        meta["tolerance_um"].get<double>() > 0)
        tolerance_um = meta["tolerance_um"].get<double>();
    out.payload_json = storage::circular_result_json(out.result, out.trace, tolerance_um);
    store.add_result(id, "circular", out.payload_json, std::nullopt, "ballbar circular/1");
    return out;
}

PreparedCircular resume_circular_session(storage::Store& store, const std::string& key, analysis::NcDialect dialect,
                                         double dwell_s) {
    PreparedCircular p;
    p.dialect = dialect;
    p.dwell_s = dwell_s;
    const std::int64_t id = store.find_session(key);  // StorageError not_found: "no session …"
    p.before = store.session(id);
    const storage::SessionInfo& before = *p.before;
    if (before.procedure != "circular")
        throw Error(ErrorCategory::bad_input, "session " + std::to_string(id) +
                                                  " is not a circular test (procedure \"" + before.procedure +
                                                  "\"): resume it with ballbar measure");
    if (!before.resumable())
        throw Error(ErrorCategory::bad_input, "session " + std::to_string(id) + " is " +
                                                  std::string(storage::to_string(before.state)) +
                                                  ": only an interrupted or failed session can be resumed");
    p.test = storage::load_trace(store, id).test;
    const ojson meta = ojson::parse(before.metadata_json.empty() ? "{}" : before.metadata_json, nullptr, false);
    if (meta.is_object() && meta.contains("part_program") && meta["part_program"].is_object()) {
        const auto& pp = meta["part_program"];
        if (const auto d = analysis::parse_nc_dialect(pp.value("dialect", "fanuc"))) p.dialect = *d;
        if (pp.contains("dwell_s") && pp["dwell_s"].is_number()) p.dwell_s = pp["dwell_s"].get<double>();
    }
    for (const auto& r : store.results(id))
        if (r.kind == "circular.attempt") ++p.first_attempt;
    store.resume_session(id);
    p.session = id;
    return p;
}

// ---- the measurement ------------------------------------------------------------------------------------

CircularMeasureResult measure_circular(storage::Store& store, const PreparedCircular& prepared, acq::Operator& op,
                                       const CircularMeasureOptions& o) {
    CircularMeasureResult out;
    out.test = prepared.test;
    const std::string uri = o.device_uri;
    const auto create = [&]() {
        const std::int64_t id = create_circular_session(
            store, out.test, prepared.dialect, prepared.dwell_s,
            uri.starts_with("emulator:") ? storage::SessionSource::emulator : storage::SessionSource::device,
            o.operator_name, o.notes, o.machine ? &*o.machine : nullptr, o.tolerance_um, o.machine_asset);
        if (o.on_session_created) o.on_session_created(id, out.test);
        return id;
    };
    std::optional<CircularStoreSink> sink_storage;
    if (prepared.session)
        sink_storage.emplace(store, *prepared.session, out.test.radius_mm);
    else
        sink_storage.emplace(store, CircularStoreSink::Create(create), out.test.radius_mm);
    CircularStoreSink& sink = *sink_storage;
    const OpenedSource opened = open_source(uri, out.test.radius_mm, o.open_transport);
    if (opened.ballbar)
        opened.ballbar->on_identified = [&sink](const device::InstrumentInfo& info) { sink.identified(info); };
    acq::CircularOptions options;
    options.stop = o.stop;
    options.dwell_s = prepared.dwell_s;
    options.first_attempt = prepared.first_attempt;
    options.fit_feed_in = o.fit_feed_in && !prepared.session;
    sink.test_fitted = [&](const circ::TestSpec& fitted) {
        out.test = fitted;
        if (o.on_test_fitted) o.on_test_fitted(fitted);
    };
    const std::uint64_t first_seq = prepared.session ? store.next_seq(*prepared.session) : 0;
    acq::CircularSession session(out.test, opened.source(), sink, op, options);
    out.summary = session.run();
    sink.finish(out.summary);
    out.session_id = sink.id();
    if (opened.gauge && out.session_id) store_gauge_instrument(store, *out.session_id, *opened.gauge, first_seq);
    if (out.summary.final_state == acq::State::Done && out.session_id)
        out.stored = analyze_stored_circular(store, *out.session_id);
    return out;
}

void throw_unless_completed(const acq::CircularSummary& sum, std::optional<std::int64_t> id,
                            const std::string& resume_hint) {
    if (sum.final_state == acq::State::Done) return;
    if (!id) {  // refused or failed before the session was made: nothing stored
        throw Error(sum.refused ? ErrorCategory::bad_input : ErrorCategory::failed, sum.reason);
    }
    const std::string session = "session " + std::to_string(*id);
    if (sum.interrupted)
        throw Error(ErrorCategory::interrupted,
                    session + " interrupted after " + std::to_string(sum.samples) + " samples (" + sum.reason +
                        "); everything measured is stored" +
                        (resume_hint.empty() ? std::string(" (a demo session is not resumed: run the demo again)")
                                             : ". Continue it with: " + resume_hint));
    if (sum.refused) throw Error(ErrorCategory::bad_input, session + ": " + sum.reason);
    if (sum.final_state == acq::State::Aborted)
        throw Error(ErrorCategory::interrupted, session + " aborted: " + sum.reason);
    throw Error(ErrorCategory::failed, session + " failed: " + sum.reason);
}

}  // namespace ballbar::workflow
