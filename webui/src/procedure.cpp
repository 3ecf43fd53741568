// SPDX-License-Identifier: MIT
#include "ballbar/webui/procedure.hpp"

#include <cmath>
#include <limits>
#include <sstream>

#include "ballbar/acquisition/circle_program.hpp"
#include "ballbar/acquisition/machine_file.hpp"
#include "ballbar/acquisition/plan.hpp"
#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/device/emulator.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/circular_demo.hpp"
#include "ballbar/workflow/circular_measure.hpp"
#include "ballbar/workflow/circular_test.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/measure.hpp"
#include "ballbar/workflow/ssm_demo.hpp"

namespace ballbar::webui {

namespace acq = ballbar::acquisition;
namespace ba = ballbar::analysis;
namespace circ = ballbar::analysis::circular;
using json = nlohmann::json;

namespace {

constexpr std::size_t kStopped = std::numeric_limits<std::size_t>::max();
constexpr std::size_t kLogLines = 200;

// The steps a page shows ("Step 3 of 6: Set-up"); the same six for both procedures.
const std::vector<std::string> kSteps = {"Connect", "Reference", "Set-up", "Measure", "Review", "Results"};

int step_of_question(const std::string& what) {
    if (what == "reference" || what == "reference-declined") return 2;
    if (what == "setup" || what == "temperature") return 3;
    if (what == "review") return 5;
    return 4;
}

double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

std::string where(const acq::PlannedPoint& p) {
    return "test " + std::to_string(p.test + 1) + " step " + std::to_string(p.step) + " point " +
           std::to_string(p.point + 1);
}

/// A demo's "faults" (the emulator's "faults" object of docs/emulator.md: a dropped link, lost frames, …);
/// none when the request has none. Throws ApiError (400) on one the emulator would refuse.
device::FaultConfig demo_faults(const json& request) {
    const auto it = request.find("faults");
    if (it == request.end() || it->is_null()) return {};
    if (!it->is_object()) throw ApiError(400, "\"faults\" must be an object (docs/emulator.md)");
    try {
        return device::parse_emulator_config(json{{"faults", *it}}.dump()).faults;
    } catch (const std::exception& e) {
        throw ApiError(400, std::string("\"faults\": ") + e.what());
    }
}

}  // namespace

// ---- the operator at the page ------------------------------------------------------------------------

class Procedure::WebOperator : public acq::Operator {
  public:
    explicit WebOperator(Procedure& p) : p_(p) {}

    bool confirm(std::string_view what, std::string_view prompt) override {
        Question q;
        q.kind = "confirm";
        q.what = std::string(what);
        q.prompt = std::string(prompt);
        if (what == "review") {
            q.options = {"Accept", "Measure again"};
        } else {
            q.options = {"Yes"};
            q.not_yet = "Not yet";  // answers nothing: the question stays until Yes (or the stop button)
        }
        return p_.ask(std::move(q)) == 0;
    }
    std::size_t choose(const acq::Choice& c) override {
        Question q;
        q.kind = "choose";
        q.what = c.what;
        q.prompt = c.prompt;
        q.options = c.options;
        const std::size_t a = p_.ask(std::move(q));
        if (a != kStopped) return a;
        for (std::size_t i = 0; i < c.options.size(); ++i)  // stopped: the option that ends the session
            if (c.options[i] == "abort" || c.options[i] == "stop") return i;
        return c.default_option;
    }
    void message(std::string_view text) override {
        std::lock_guard lk(p_.mu_);
        p_.log(std::string(text));
        p_.bump();
    }
    acq::PointFailureAction point_failed(const acq::CapturedPoint& pt, std::string_view why) override {
        Question q;
        q.kind = "choose";
        q.what = "point-failed";
        q.prompt = "Point " + where(pt.planned) + " failed its checks on every attempt: " + std::string(why);
        q.options = {"retry", "accept", "abort"};
        switch (p_.ask(std::move(q))) {
            case 0:
                return acq::PointFailureAction::Retry;
            case 1:
                return acq::PointFailureAction::Accept;
            default:
                return acq::PointFailureAction::Abort;
        }
    }
    void wait_at_point(const acq::PlannedPoint& pt) override {
        Question q;
        q.kind = "acknowledge";
        q.what = "at-point";
        std::ostringstream os;
        os << "Move the machine to " << where(pt) << " (X " << pt.pose.X_mm << " Y " << pt.pose.Y_mm << " Z "
           << pt.pose.Z_mm << ") and say when it stands there.";
        q.prompt = os.str();
        q.options = {"The machine stands at the point"};
        p_.ask(std::move(q));
    }
    void progress(const acq::Progress& pr) override {
        std::lock_guard lk(p_.mu_);
        LiveReading& l = p_.live_;
        ++l.seq;
        l.bar_mm = pr.live_mm;
        l.expected_mm = pr.expected_mm;
        l.range_mm = pr.range_mm;
        l.out_of_range = pr.out_of_range;
        l.fill = pr.fill;
        json& s = p_.state_;
        json& g = s["progress"];
        if (!g.is_object()) g = json::object();
        const bool moved = g.value("done", std::size_t{0}) != pr.done || g.value("test", -1) != pr.test ||
                           g.value("point", -1) != pr.point;
        g = {{"done", pr.done},
             {"total", pr.total},
             {"test", pr.test},
             {"step", pr.step},
             {"point", pr.point},
             {"time_left_s", pr.time_left_s},
             {"at_ms", ms_since(p_.started_)}};
        if (p_.state_.value("step", json::object()).value("n", 0) < 4) p_.set_step(4);
        if (moved) p_.bump();  // a new reading alone wakes nobody: the streams look at it on their 50 Hz tick
    }
    void run_program(const ba::NcProgram& program, std::span<const std::size_t> points, bool retry) override {
        {
            std::lock_guard lk(p_.mu_);
            p_.state_["program"] = {
                {"text", ba::write_nc_program(program, "ballbar SSM")}, {"points", points.size()}, {"retry", retry}};
        }
        Question q;
        q.kind = "acknowledge";
        q.what = "run-program";
        q.prompt = std::string(retry ? "Run the retry program for the missing points" : "Run the measuring program") +
                   " (" + std::to_string(points.size()) +
                   " points): load it on the controller (download it below) and press cycle start.";
        q.options = {"Program loaded, cycle start pressed"};
        p_.ask(std::move(q));
    }
    void program_stop(const acq::ProgramStop& stop) override {
        Question q;
        q.kind = "acknowledge";
        q.what = "program-stop";
        q.prompt = "The program stopped (M0): " + stop.what + (stop.what.ends_with('.') ? "" : ".");
        q.options = {"Done, cycle start pressed"};
        if (stop.socket_mm) {
            std::lock_guard lk(p_.mu_);
            p_.state_["socket_mm"] = {stop.socket_mm->x(), stop.socket_mm->y(), stop.socket_mm->z()};
        }
        p_.ask(std::move(q));
    }
    void point_captured(const acq::CapturedPoint& c) override {
        std::lock_guard lk(p_.mu_);
        const double dev_um = (c.measured_mm - c.planned.nominal_mm) * 1e3;
        p_.state_["points"].push_back({{"test", c.planned.test + 1},
                                       {"step", c.planned.step},
                                       {"point", c.planned.point + 1},
                                       {"measured_mm", c.measured_mm},
                                       {"nominal_mm", c.planned.nominal_mm},
                                       {"deviation_um", dev_um},
                                       {"std_um", c.std_mm * 1e3},
                                       {"n", c.n},
                                       {"verdict", c.operator_accepted ? "kept by the operator" : "ok"}});
        json& g = p_.state_["progress"];
        if (g.is_object() && g.contains("done")) g["done"] = g["done"].get<std::size_t>() + 1;
        p_.bump();
    }
    void run_part_program(std::string_view what, bool retry) override {
        Question q;
        q.kind = "acknowledge";
        q.what = "run-part-program";
        q.prompt = std::string(what);
        q.options = {retry ? "Started again, cycle start pressed" : "Program loaded, cycle start pressed"};
        p_.ask(std::move(q));
    }
    void instrument_lost(double timeout_s) override {
        std::lock_guard lk(p_.mu_);
        p_.state_["lost"] = {{"timeout_s", timeout_s}, {"at_ms", ms_since(p_.started_)}};
        p_.log("Instrument lost: check its cable (or radio link), its battery and that it is switched on.");
        p_.bump();
    }
    void instrument_back() override {
        std::lock_guard lk(p_.mu_);
        p_.state_["lost"] = nullptr;
        p_.log("Instrument back.");
        p_.bump();
    }

  private:
    Procedure& p_;
};

// ---- the procedure ----------------------------------------------------------------------------------

Procedure::Procedure(std::string db_path)
    : db_path_(std::move(db_path)), operator_(std::make_unique<WebOperator>(*this)) {
    state_ = {{"running", false}, {"state", "idle"}};
}

acq::Operator& Procedure::web_operator() {
    return *operator_;
}

Procedure::~Procedure() {
    shutdown();
}

void Procedure::bump() {
    ++version_;
    changed_.notify_all();
}

void Procedure::log(const std::string& text) {
    log_.push_back({{"t_s", ms_since(started_) / 1e3}, {"text", text}});
    while (log_.size() > kLogLines) log_.pop_front();
}

void Procedure::set_step(int step) {
    state_["step"] = {{"n", step}, {"of", kSteps.size()}, {"name", kSteps[static_cast<std::size_t>(step - 1)]}};
}

void Procedure::check_driver(const std::string& client) {
    if (client.empty()) throw ApiError(400, "no client id (X-Ballbar-Client header)");
    if (client == driver_) return;
    const auto it = streams_.find(driver_);
    if (it != streams_.end() && it->second > 0)
        throw ApiError(403, "another screen steers this procedure: this one may watch it");
    driver_ = client;  // the screen that steered has gone: this one takes over
    log("Another screen took over the procedure.");
}

std::size_t Procedure::ask(Question q) {
    std::unique_lock lk(mu_);
    q.id = ++question_seq_;
    q.step = step_of_question(q.what);
    set_step(q.step);
    if (q.step != 4 && state_["progress"].is_object()) state_["progress"]["time_left_s"] = 0;  // no program runs
    log("Asked: " + q.prompt);
    question_ = std::move(q);
    answer_.reset();
    bump();
    changed_.wait(lk, [&] { return answer_.has_value() || stop_.load(); });
    const std::size_t a = answer_.value_or(kStopped);
    if (answer_) log("Answered: " + question_->options[a]);
    question_.reset();
    answer_.reset();
    bump();
    return a;
}

json Procedure::start(const json& request, const std::string& client) {
    if (!request.is_object()) throw ApiError(400, "the request must be a JSON object");
    const std::string procedure = request.value("procedure", "");
    if (procedure != "ssm" && procedure != "circular")
        throw ApiError(400, "\"procedure\" must be \"ssm\" or \"circular\"");
    const bool demo = request.value("demo", false);
    const std::string device = request.value("device", "");
    const std::string resume = request.value("resume", "");
    if (!demo && device.empty())
        throw ApiError(400, "give \"device\" (a device URI, as `ballbar devices` lists them) or \"demo\": true");
    if (demo && !resume.empty()) throw ApiError(400, "a demo session is not resumed: give \"device\" to resume");
    if (!demo && resume.empty() && procedure == "ssm" &&
        (!request.contains("machine_file") || !request.contains("plan_file")))
        throw ApiError(400, "an SSM measurement needs \"machine_file\" and \"plan_file\" (their JSON text)");
    if (!demo && request.contains("faults"))
        throw ApiError(400, "\"faults\" are the emulator's: only a demo takes them");
    demo_faults(request);  // refused here, not on the procedure's thread
    if (client.empty()) throw ApiError(400, "no client id (X-Ballbar-Client header)");
    std::lock_guard lk(mu_);
    if (running_) throw ApiError(409, "a procedure is running: one screen steers it, others watch");
    if (thread_.joinable()) thread_.join();  // the last one has ended
    stop_ = false;
    running_ = true;
    driver_ = client;
    started_ = std::chrono::steady_clock::now();
    log_.clear();
    question_.reset();
    answer_.reset();
    live_ = {};
    state_ = {{"running", true},    {"state", "running"}, {"procedure", procedure},  {"demo", demo},
              {"session", nullptr}, {"steps", kSteps},    {"points", json::array()}, {"progress", json::object()},
              {"lost", nullptr},    {"program", nullptr}, {"result", nullptr},       {"message", nullptr}};
    set_step(1);
    log(std::string("Started: ") + (procedure == "ssm" ? "two-step SSM" : "ISO 230-4 circular test") +
        (demo ? " on the emulator (demo)" : " on " + device));
    bump();
    thread_ = std::thread([this, request] { run(request); });
    return {{"started", true}, {"procedure", procedure}};
}

void Procedure::answer(std::uint64_t question, std::size_t option, const std::string& client) {
    std::lock_guard lk(mu_);
    if (!running_) throw ApiError(409, "no procedure is running");
    check_driver(client);
    if (!question_ || question_->id != question)
        throw ApiError(409, "question " + std::to_string(question) + " is not being asked (answered already?)");
    if (option >= question_->options.size())
        throw ApiError(400, "option " + std::to_string(option) + " is not one of the question's " +
                                std::to_string(question_->options.size()));
    if (answer_) throw ApiError(409, "question " + std::to_string(question) + " is answered already");
    answer_ = option;
    changed_.notify_all();
}

void Procedure::stop(const std::string& client) {
    std::lock_guard lk(mu_);
    if (!running_) throw ApiError(409, "no procedure is running");
    check_driver(client);
    log("Stop asked: the session stops, keeping what it measured (resumable).");
    stop_ = true;
    bump();
}

void Procedure::shutdown() {
    {
        std::lock_guard lk(mu_);
        stop_ = true;
        changed_.notify_all();
    }
    if (thread_.joinable()) thread_.join();
}

void Procedure::finish(const std::string& state, const std::string& message) {
    std::lock_guard lk(mu_);
    running_ = false;
    question_.reset();
    state_["running"] = false;
    state_["state"] = state;
    state_["message"] = message;
    state_["lost"] = nullptr;
    set_step(state == "completed" ? 6 : state_.value("step", json::object()).value("n", 1));
    log(message);
    bump();
}

void Procedure::run(json request) {
    const std::string procedure = request.value("procedure", "");
    const bool demo = request.value("demo", false);
    WebOperator& op = *operator_;
    auto set_session = [this](std::int64_t id) {
        std::lock_guard lk(mu_);
        state_["session"] = id;
        log("Session " + std::to_string(id) + " stored.");
        bump();
    };
    std::optional<std::int64_t> session;
    try {
        storage::StoreOptions so;
        so.sync_full = !demo;  // a demo does not need an fsync per commit
        storage::Store store(db_path_, so);
        json result;
        if (procedure == "circular") {
            workflow::CircularTestInput in;
            in.plane = request.value("plane", "XY");
            in.radius_mm = request.value("radius_mm", 100.0);
            in.feed_mm_min = request.value("feed_mm_min", 1000.0);
            in.feed_in_mm = demo ? 0.8 : request.value("feed_in_mm", 1.5);  // the demo bar's ±1 mm range
            in.arc_deg = request.value("arc_deg", in.plane == "XY" ? 360.0 : 180.0);
            if (demo) {
                workflow::CircularDemoOptions d;
                d.test = workflow::circular_test_spec(in);
                d.seed = request.value("seed", std::uint64_t{1});
                d.notes = "ballbar serve: circular demo";
                d.faults = demo_faults(request);
                d.stop = &stop_;
                d.on_started = [&](const std::string&, std::int64_t id) {
                    session = id;
                    set_session(id);
                };
                const auto r = workflow::run_circular_demo(store, d, op);
                result = {{"pass", r.pass}, {"bidirectional_um", r.result.bidirectional_um.value_or(NAN)}};
                for (const auto& run : r.result.runs)
                    result["runs"].push_back(
                        {{"direction", circ::direction_name(run.direction)}, {"circularity_um", run.circularity_um}});
            } else {
                workflow::PreparedCircular prepared;
                const std::string resume = request.value("resume", "");
                if (!resume.empty()) {
                    prepared = workflow::resume_circular_session(store, resume);
                    session = prepared.session;
                    if (session) set_session(*session);
                } else {
                    prepared.test = workflow::circular_test_spec(in);
                    const auto dialect = ba::parse_nc_dialect(request.value("dialect", "fanuc"));
                    if (!dialect)
                        throw workflow::Error(workflow::ErrorCategory::bad_input,
                                              "\"dialect\" must be \"fanuc\" or \"linuxcnc\"");
                    prepared.dialect = *dialect;
                }
                // The part program the operator downloads from the page and loads on the controller; a
                // feed-in fitted to the bar's range changes it before it is asked for.
                const auto offer_program = [this, &prepared](const circ::TestSpec& test) {
                    std::string text = acq::circular_program(test, prepared.dialect, prepared.dwell_s);
                    std::lock_guard lk(mu_);
                    state_["program"] = {{"text", std::move(text)}, {"runs", test.runs.size()}, {"retry", false}};
                    bump();
                };
                offer_program(prepared.test);
                workflow::CircularMeasureOptions mo;
                mo.device_uri = request.value("device", "");
                mo.operator_name = request.value("operator", "");
                mo.notes = "ballbar serve";
                if (request.contains("machine_file"))  // the machine tested: listed and trended under it
                    mo.machine = acq::parse_machine_file(request.at("machine_file").get<std::string>()).geometry;
                mo.fit_feed_in = resume.empty();
                mo.stop = &stop_;
                mo.on_session_created = [&](std::int64_t id, const circ::TestSpec&) {
                    session = id;
                    set_session(id);
                };
                mo.on_test_fitted = offer_program;
                const auto r = workflow::measure_circular(store, prepared, op, mo);
                workflow::throw_unless_completed(r.summary, r.session_id, "the Resume button of the session's page.");
                if (r.stored)
                    for (const auto& run : r.stored->result.runs)
                        result["runs"].push_back({{"direction", circ::direction_name(run.direction)},
                                                  {"circularity_um", run.circularity_um}});
            }
        } else if (demo) {
            workflow::SsmDemoOptions d;
            const auto type = ba::parse_machine_type(request.value("machine", "TTTRR"));
            if (!type)
                throw workflow::Error(workflow::ErrorCategory::bad_input, "machine must be RRTTT, TTTRR or RTTTR");
            d.machine = *type;
            d.seed = request.value("seed", std::uint64_t{1});
            d.notes = "ballbar serve: SSM demo";
            d.faults = demo_faults(request);
            d.front = &op;
            d.stop = &stop_;
            workflow::SsmDemoEvents ev;
            ev.started = [&](std::int64_t id, const acq::Plan& plan, const std::string&) {
                session = id;
                set_session(id);
                std::lock_guard lk(mu_);
                const ba::Vec3& s = plan.spec.tests.front().socket_mm;
                state_["socket_mm"] = {s.x(), s.y(), s.z()};
                state_["tests"] = plan.test_count();
            };
            const auto r = workflow::run_ssm_demo(store, d, ev);
            result = {
                {"points", r.check.points}, {"wrong_pose", r.check.wrong_pose}, {"tests", r.summary.tests.size()}};
        } else {
            workflow::PreparedSession prepared;
            const std::string resume = request.value("resume", "");
            if (!resume.empty()) {
                prepared = workflow::resume_ssm_session(store, resume);
            } else {
                const acq::MachineFile machine = acq::parse_machine_file(request.at("machine_file").get<std::string>());
                const acq::PlanSpec spec =
                    acq::parse_plan_file(request.at("plan_file").get<std::string>(), machine.geometry.type);
                prepared = workflow::new_ssm_session(store, acq::make_plan(machine, spec), request.value("device", ""));
            }
            session = prepared.id;
            set_session(prepared.id);
            workflow::SsmMeasureOptions mo;
            mo.device_uri = request.value("device", "");
            mo.plan_file = "the page's plan";
            mo.stop = &stop_;
            const auto sum = workflow::measure_ssm(store, prepared, op, mo);
            if (sum.final_state != acq::State::Done) {
                const std::string how = sum.interrupted ? "interrupted" : "ended";
                throw workflow::Error(
                    sum.interrupted ? workflow::ErrorCategory::interrupted : workflow::ErrorCategory::failed,
                    "session " + std::to_string(prepared.id) + " " + how + ": " + sum.reason);
            }
            result = {{"tests", sum.tests.size()}};
        }
        {
            std::lock_guard lk(mu_);
            state_["result"] = result;
        }
        finish("completed", "Completed: session " + (session ? std::to_string(*session) : std::string("-")) +
                                " stored with its results.");
    } catch (const workflow::Error& e) {
        const bool interrupted = e.category() == workflow::ErrorCategory::interrupted || stop_.load();
        const std::string what = e.what();
        const bool said = what.find("everything measured is stored") != std::string::npos;
        finish(interrupted ? "interrupted" : "failed",
               what + (interrupted && session && !said ? " Everything measured is stored." : ""));
    } catch (const std::exception& e) {
        const auto category = workflow::category_of(e);
        finish(category == workflow::ErrorCategory::interrupted ? "interrupted" : "failed", e.what());
    }
}

json Procedure::snapshot(const std::string& client) const {
    std::lock_guard lk(mu_);
    json s = state_;
    const auto d = streams_.find(driver_);
    s["you_steer"] = !running_ || client == driver_ || d == streams_.end();
    s["version"] = version_;
    s["log"] = json::array();
    for (const auto& l : log_) s["log"].push_back(l);
    s["question"] = nullptr;
    if (question_ && !answer_) {  // an answered question is not shown while its thread wakes
        s["question"] = {{"id", question_->id},
                         {"kind", question_->kind},
                         {"what", question_->what},
                         {"prompt", question_->prompt},
                         {"options", question_->options}};
        if (!question_->not_yet.empty()) s["question"]["not_yet"] = question_->not_yet;
    }
    s["now_ms"] = ms_since(started_);
    s["viewers"] = 0;
    for (const auto& [c, n] : streams_) s["viewers"] = s["viewers"].get<int>() + n;
    return s;
}

std::uint64_t Procedure::version() const {
    std::lock_guard lk(mu_);
    return version_;
}

LiveReading Procedure::live() const {
    std::lock_guard lk(mu_);
    return live_;
}

void Procedure::wait_change(std::uint64_t version, std::chrono::milliseconds timeout) const {
    std::unique_lock lk(mu_);
    changed_.wait_for(lk, timeout, [&] { return version_ != version; });
}

void Procedure::viewer(const std::string& client, bool open) {
    std::lock_guard lk(mu_);
    int& n = streams_[client];
    n += open ? 1 : -1;
    if (n <= 0) streams_.erase(client);
    bump();
}

std::size_t Procedure::viewers() const {
    std::lock_guard lk(mu_);
    std::size_t n = 0;
    for (const auto& [c, k] : streams_) n += static_cast<std::size_t>(k);
    return n;
}

}  // namespace ballbar::webui
