// SPDX-License-Identifier: MIT
#include "ballbar/workflow/measure.hpp"

#include "ballbar/acquisition/bar_check.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/gauge_source.hpp"
#include "ballbar/workflow/session_io.hpp"

namespace ballbar::workflow {

namespace acq = ballbar::acquisition;

PreparedSession new_ssm_session(storage::Store& store, const acq::Plan& plan, std::string_view device_uri,
                                const std::string& machine_asset) {
    PreparedSession s;
    s.plan = plan;
    storage::NewSession ns;
    ns.machine = plan.machine.geometry;
    ns.machine_asset = machine_asset;
    ns.source = device_uri.starts_with("emulator:") ? storage::SessionSource::emulator : storage::SessionSource::device;
    ns.operator_name = plan.spec.answers.operator_name;
    ns.procedure = "ssm-two-step";
    s.id = store.create_session(ns);
    store.start_session(s.id);
    store_plan(store, s.id, plan);
    return s;
}

PreparedSession resume_ssm_session(storage::Store& store, std::string_view key) {
    PreparedSession s;
    s.id = store.find_session(std::string(key));  // StorageError not_found: "no session …"
    s.before = store.session(s.id);
    try {
        s.plan = load_plan(store, s.id);
    } catch (const acq::PlanError& e) {
        throw Error(ErrorCategory::bad_input, e.what());
    }
    try {
        s.done = load_points(store, s.id, s.plan);
    } catch (const acq::PlanError& e) {  // stored points the stored plan has no place for: the data's fault
        throw Error(ErrorCategory::failed, "session " + std::to_string(s.id) + ": " + e.what());
    }
    try {
        store.resume_session(s.id);
    } catch (const storage::StorageError& e) {
        // A completed or aborted session, or one another process is measuring: the request contradicts
        // the session's state, and changes nothing.
        if (e.kind() != storage::StorageError::Kind::invalid) throw;
        throw Error(ErrorCategory::bad_input, e.what());
    }
    return s;
}

acq::SessionSummary measure_ssm(storage::Store& store, const PreparedSession& prepared, acq::Operator& op,
                                const SsmMeasureOptions& o) {
    const std::int64_t id = prepared.id;
    const acq::Plan& plan = prepared.plan;
    const std::string uri = o.device_uri;
    const OpenedSource opened = open_source(uri, plan.spec.bar_length_mm, o.open_transport);
    if (opened.ballbar)
        opened.ballbar->on_identified = [&store, id, &plan, &o](const device::InstrumentInfo& info) {
            store.set_instrument(id, stored_instrument(info));  // sessions show, the report
            const std::string mismatch = acq::bar_length_mismatch(plan.spec.bar_length_mm, info.calibrated_length_mm,
                                                                  plan.spec.capture.tolerance_mm, o.plan_file);
            if (!mismatch.empty()) throw acq::InstrumentUnfit(mismatch);
        };
    StoreSink sink(store, id, plan);
    acq::SessionOptions options;
    options.stop = o.stop;
    acq::Session session(plan, opened.source(), sink, op, options);
    try {
        session.restore(prepared.done);
    } catch (const acq::PlanError& e) {  // as in resume_ssm_session: the stored data's fault
        throw Error(ErrorCategory::failed, "session " + std::to_string(id) + ": " + e.what());
    }
    const std::uint64_t first_seq = store.next_seq(id);  // this run's samples (a resume continues after)
    const acq::SessionSummary sum = session.run();
    sink.finish(sum);
    if (opened.gauge) store_gauge_instrument(store, id, *opened.gauge, first_seq);  // identity, resolution, rate
    if (opened.ballbar) store_bar_resolution(store, id, *opened.ballbar, first_seq);
    return sum;
}

}  // namespace ballbar::workflow
