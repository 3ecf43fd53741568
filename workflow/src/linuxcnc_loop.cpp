// SPDX-License-Identifier: MIT
#include "ballbar/workflow/linuxcnc_loop.hpp"

#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <random>
#include <thread>

#include "ballbar/acquisition/circle_program.hpp"
#include "ballbar/acquisition/compute.hpp"
#include "ballbar/acquisition/result_codec.hpp"
#include "ballbar/acquisition/session.hpp"
#include "ballbar/analysis/effects.hpp"
#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/analysis/nc_program.hpp"
#include "ballbar/device/trajectory.hpp"
#include "ballbar/device/uri.hpp"
#include "ballbar/storage/compensation_codec.hpp"
#include "ballbar/storage/model_codec.hpp"
#include "ballbar/workflow/circular_measure.hpp"
#include "ballbar/workflow/discover.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/identify.hpp"
#include "ballbar/workflow/pty_emulator.hpp"
#include "ballbar/workflow/session_io.hpp"
#include "ballbar/workflow/ssm_demo.hpp"
#include "linuxcnc_config.hpp"

extern char** environ;

namespace ballbar::workflow {

namespace acq = ballbar::acquisition;
namespace ba = ballbar::analysis;
namespace circ = ballbar::analysis::circular;
namespace fs = std::filesystem;

namespace {

constexpr const char* kModuleDir = "/usr/lib/linuxcnc/modules";
constexpr unsigned kRtapiUid = 65534;  // nobody: rtapi_app refuses to run with a real uid of 0
constexpr double kDegree = 3.14159265358979323846 / 180.0;
constexpr double kCircleA_deg = 30.0;  // the loop's circular test: the table tilted

fs::path module_link() {
    return fs::path(kModuleDir) / "ballbarkins.so";
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
    for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
        s.replace(at, from.size(), to);
    return s;
}

void write_text(const fs::path& p, const std::string& text, mode_t mode = 0644) {
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    if (!out) throw Error(ErrorCategory::failed, "cannot write " + p.string());
    ::chmod(p.c_str(), mode);
}

std::uint32_t fnv1a(const std::string& bytes) {
    std::uint32_t h = 2166136261u;
    for (const unsigned char c : bytes) h = (h ^ c) * 16777619u;
    return h;
}

/// write(2) to a pipe whose reader may be gone (LinuxCNC stopped): EPIPE, not a SIGPIPE that would end
/// this process. SIGPIPE is blocked in this thread for the call and a pending one consumed.
ssize_t write_no_sigpipe(int fd, const char* data, std::size_t n) {
    sigset_t pipe_set, old;
    sigemptyset(&pipe_set);
    sigaddset(&pipe_set, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &pipe_set, &old);
    const ssize_t r = ::write(fd, data, n);
    const int err = errno;
    if (r < 0 && err == EPIPE) {
        const timespec none{0, 0};
        sigtimedwait(&pipe_set, nullptr, &none);
    }
    pthread_sigmask(SIG_SETMASK, &old, nullptr);
    errno = err;
    return r;
}

/// Why LinuxCNC's user (RTAPI_UID) cannot reach `dir` (every directory above it must let others search
/// it): empty when it can. Only a root run has that user.
std::string unreachable_by_rtapi(const fs::path& dir) {
    if (::geteuid() != 0) return {};
    for (fs::path p = fs::absolute(dir); !p.empty(); p = p.parent_path()) {
        struct stat st {};
        if (::stat(p.c_str(), &st) == 0 && (st.st_mode & S_IXOTH) == 0)
            return p.string() + " does not let others search it (LinuxCNC's real-time process runs as uid " +
                   std::to_string(kRtapiUid) + " and reads its module, configuration and model below it)";
        if (p == p.root_path()) break;
    }
    return {};
}

bool process_running(const char* name) {
    const std::string cmd = std::string("pgrep -x ") + name + " > /dev/null 2>&1";
    return std::system(cmd.c_str()) == 0;
}

/// LinuxCNC's System V shared-memory keys (LinuxCNC 2.9: HAL, the uspace RTAPI, motion's
/// DEFAULT_MOTION_SHMEM_KEY, the NML buffers of emc.nml, the samplers and streamers).
bool linuxcnc_shm_key(long key) {
    return key == 0x48414c32 || key == 0x48484c34 || key == 100 || (key >= 1001 && key <= 1005) ||
           (key >= 0x48534130 && key <= 0x48534137) || (key >= 0x48535430 && key <= 0x48535437);
}

/// Why LinuxCNC cannot be started here (empty when it can): one already running (it runs once per
/// machine), or the shared memory of one that did not shut down (a killed LinuxCNC leaves it, and the
/// next one fails on it, or reads it). ballbar frees neither: they are not its own.
std::string linuxcnc_in_the_way() {
    for (const char* p : {"rtapi_app", "milltask", "linuxcncsvr"})
        if (process_running(p))
            return std::string("LinuxCNC is already running on this machine (") + p +
                   "): it runs once per machine, and the loop starts its own simulator; stop it first";
    std::ifstream shm("/proc/sysvipc/shm");
    std::string line, keys;
    std::getline(shm, line);  // the column names
    while (std::getline(shm, line)) {
        long key = 0;
        if (std::sscanf(line.c_str(), "%ld", &key) == 1 && linuxcnc_shm_key(key)) {
            char hex[16];
            std::snprintf(hex, sizeof hex, "0x%08lx", static_cast<unsigned long>(key) & 0xffffffffUL);
            keys += std::string(keys.empty() ? "" : " ") + hex;
        }
    }
    if (!keys.empty())
        return "the shared memory of a LinuxCNC that did not shut down is still there (keys " + keys +
               "; a killed LinuxCNC leaves it): free it with `halrun -U`, then `ipcrm -M KEY` for each key left";
    return {};
}

/// LinuxCNC started on one configuration, its display taking commands and telling events.
class Linuxcnc {
  public:
    Linuxcnc(const fs::path& cfg_dir, const std::string& ini, const fs::path& log_path) {
        if (const std::string why = linuxcnc_in_the_way(); !why.empty())
            throw Error(ErrorCategory::device, "LinuxCNC cannot be started: " + why);
        log_.open(log_path, std::ios::binary | std::ios::trunc);
        int in[2], out[2];
        if (::pipe2(in, O_CLOEXEC) != 0 || ::pipe2(out, O_CLOEXEC) != 0)
            throw Error(ErrorCategory::device, "cannot make pipes for LinuxCNC");
        posix_spawn_file_actions_t fa;
        posix_spawn_file_actions_init(&fa);
        posix_spawn_file_actions_adddup2(&fa, in[0], 0);
        posix_spawn_file_actions_adddup2(&fa, out[1], 1);
        posix_spawn_file_actions_adddup2(&fa, out[1], 2);
        posix_spawn_file_actions_addchdir_np(&fa, cfg_dir.c_str());
        std::vector<std::string> env;
        for (char** e = environ; *e; ++e) {
            const std::string_view v(*e);
            if (v.rfind("RTAPI_", 0) != 0) env.emplace_back(v);
        }
        if (::geteuid() == 0) {
            const fs::path fifo = cfg_dir.parent_path() / "rtapi";
            fs::create_directories(fifo);
            if (::chown(fifo.c_str(), kRtapiUid, static_cast<gid_t>(-1)) != 0) {
            }
            env.push_back("RTAPI_UID=" + std::to_string(kRtapiUid));
            env.push_back("RTAPI_FIFO_PATH=" + (fifo / "socket").string());
        }
        std::vector<char*> envp;
        for (auto& e : env) envp.push_back(e.data());
        envp.push_back(nullptr);
        // Through a shell that ignores SIGPIPE (exec keeps an ignored signal ignored): should ballbar be
        // killed, the `linuxcnc` script's next line to the closed pipe would otherwise kill it before its
        // shutdown, and leave LinuxCNC's processes running and its shared memory behind. The display
        // reads the end of its input and quits; the script then shuts LinuxCNC down as at any end.
        std::string a0 = "sh", a1 = "-c", a2 = "trap '' PIPE; exec linuxcnc -r \"$0\"", a3 = ini;
        char* argv[] = {a0.data(), a1.data(), a2.data(), a3.data(), nullptr};
        const int rc = ::posix_spawn(&pid_, "/bin/sh", &fa, nullptr, argv, envp.data());
        posix_spawn_file_actions_destroy(&fa);
        ::close(in[0]);
        ::close(out[1]);
        to_display_ = in[1];
        from_ = out[0];
        if (rc != 0) {
            ::close(to_display_), ::close(from_);
            throw Error(ErrorCategory::device, std::string("cannot start linuxcnc: ") + std::strerror(rc));
        }
        reader_ = std::thread([this] { read(); });
    }
    ~Linuxcnc() { stop(); }
    Linuxcnc(const Linuxcnc&) = delete;
    Linuxcnc& operator=(const Linuxcnc&) = delete;

    void send(const std::string& line) {
        const std::string l = line + "\n";
        if (write_no_sigpipe(to_display_, l.data(), l.size()) != static_cast<ssize_t>(l.size()))
            throw Error(ErrorCategory::device,
                        "LinuxCNC's display does not take commands (LinuxCNC stopped?)" + tail());
    }

    /// Waits until `done(state, counts)` holds; Error (device) on an error event, LinuxCNC's end or the timeout.
    template <typename Done>
    void wait(Done done, double timeout_s, const std::string& what) {
        std::unique_lock lock(mutex_);
        const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
        while (!done()) {
            if (!error_.empty()) throw Error(ErrorCategory::device, "LinuxCNC: " + error_);
            if (ended_)
                throw Error(ErrorCategory::device, "LinuxCNC stopped while waiting for " + what + tail_locked());
            if (cv_.wait_until(lock, until) == std::cv_status::timeout && !done())
                throw Error(ErrorCategory::device, "LinuxCNC: no " + what + " within " +
                                                       std::to_string(static_cast<int>(timeout_s)) + " s" +
                                                       tail_locked());
        }
    }
    std::string state() {
        std::lock_guard lock(mutex_);
        return state_;
    }
    int count(const std::string& event) {
        std::lock_guard lock(mutex_);
        return event == "started" ? started_ : resumed_;
    }
    const std::string& state_locked() const { return state_; }
    int started_locked() const { return started_; }
    int resumed_locked() const { return resumed_; }
    bool ready_locked() const { return ready_; }

    /// Quits the display, waits for LinuxCNC and its real-time process to be gone.
    void stop() {
        if (pid_ <= 0) return;
        if (to_display_ >= 0) {
            const char q[] = "quit\n";
            (void)write_no_sigpipe(to_display_, q, sizeof q - 1);
            ::close(to_display_);
            to_display_ = -1;
        }
        int status = 0;
        bool gone = false;
        for (int i = 0; i < 300 && !gone; ++i) {  // 30 s for its shutdown
            gone = ::waitpid(pid_, &status, WNOHANG) == pid_;
            if (!gone) ::usleep(100'000);
        }
        if (!gone) {
            ::kill(pid_, SIGTERM);
            ::waitpid(pid_, &status, 0);
        }
        pid_ = -1;
        if (reader_.joinable()) reader_.join();
        ::close(from_);
        // `linuxcnc` returns before rtapi_app and milltask are gone: the next run must wait for them (and
        // for the shared memory they free).
        for (int i = 0; i < 200 && !linuxcnc_in_the_way().empty(); ++i) ::usleep(50'000);
    }

  private:
    void read() {
        std::string pending;
        char buf[4096];
        for (;;) {
            const ssize_t n = ::read(from_, buf, sizeof buf);
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) break;
            log_.write(buf, n);
            log_.flush();
            pending.append(buf, static_cast<std::size_t>(n));
            std::size_t start = 0;
            for (std::size_t nl; (nl = pending.find('\n', start)) != std::string::npos; start = nl + 1)
                line(pending.substr(start, nl - start));
            pending.erase(0, start);
        }
        std::lock_guard lock(mutex_);
        ended_ = true;
        cv_.notify_all();
    }
    void line(const std::string& l) {
        std::lock_guard lock(mutex_);
        lines_.push_back(l);
        if (lines_.size() > 12) lines_.erase(lines_.begin());
        static const std::string kPrefix = "ballbar-display: ";
        if (l.rfind(kPrefix, 0) != 0) return;
        const std::string ev = l.substr(kPrefix.size());
        const std::string word = ev.substr(0, ev.find(' '));
        if (word == "error") {
            error_ = ev.size() > 6 ? ev.substr(6) : "an error";
        } else if (word == "ready" || word == "idle") {
            state_ = "idle";
        } else if (word == "started") {
            state_ = "running", ++started_;
        } else if (word == "paused") {
            state_ = "paused";
        } else if (word == "resumed") {
            state_ = "running", ++resumed_;
        }
        if (word == "ready") ready_ = true;
        cv_.notify_all();
    }
    std::string tail_locked() const {
        std::string t = "; LinuxCNC's last lines:";
        for (const auto& l : lines_) t += "\n  " + l;
        return t;
    }
    std::string tail() {
        std::lock_guard lock(mutex_);
        return tail_locked();
    }

    std::ofstream log_;
    pid_t pid_ = -1;
    int to_display_ = -1, from_ = -1;
    std::thread reader_;
    std::mutex mutex_;
    std::condition_variable cv_;
    std::string state_ = "starting", error_;
    std::vector<std::string> lines_;
    int started_ = 0, resumed_ = 0;
    bool ended_ = false, ready_ = false;
};

/// The operator at LinuxCNC's console: loads each program the procedure writes and starts it, and at
/// each program stop moves the socket where the stop says, then presses cycle start.
class LinuxcncOperator : public acq::ScriptedOperator {
  public:
    LinuxcncOperator(const acq::Plan& plan, Linuxcnc& cnc, device::SimulatedMachine& machine, fs::path dir,
                     std::string label, const LinuxcncLoopEvents& events)
        : acq::ScriptedOperator(plan.spec.answers),
          cnc_(cnc),
          machine_(machine),
          dir_(std::move(dir)),
          label_(std::move(label)),
          events_(events) {}

    void run_program(const ba::NcProgram& program, std::span<const std::size_t> points, bool retry) override {
        start(ba::write_nc_program(program, "ballbar " + label_ + (retry ? " retry" : "")),
              std::string(retry ? "retry program" : "program") + " (" + std::to_string(points.size()) + " points)");
    }
    /// The circular test's program (set_part_program), from its start.
    void run_part_program(std::string_view, bool retry) override {
        start(part_program_, retry ? "the circular test's program again" : "the circular test's program");
    }
    void set_part_program(std::string text) { part_program_ = std::move(text); }
    /// Loads `text` as the next program file and presses cycle start; returns once it runs.
    void start(const std::string& text, const std::string& what) {
        // A program still running (its points were given up on) is stopped first, as an operator would.
        if (cnc_.state() != "idle") {
            cnc_.send("abort");
            cnc_.wait([&] { return cnc_.state_locked() == "idle"; }, 30, "the program to stop");
        }
        ++programs_;
        const fs::path path = dir_ / (label_ + "-" + std::to_string(programs_) + ".ngc");
        write_text(path, text);
        const int before = cnc_.count("started");
        tell(what + " to LinuxCNC: " + path.string());
        cnc_.send("run " + path.string());
        cnc_.wait([&] { return cnc_.started_locked() > before; }, 30, "program start");
    }
    void program_stop(const acq::ProgramStop& stop) override {
        cnc_.wait([&] { return cnc_.state_locked() == "paused" || cnc_.state_locked() == "idle"; }, 600,
                  "program stop (M0)");
        if (cnc_.state() == "idle") return;  // the program ended: the procedure will see its points missing
        if (stop.socket_mm) machine_.set_socket_mm(*stop.socket_mm);
        const int before = cnc_.count("resumed");
        cnc_.send("resume");
        cnc_.wait([&] { return cnc_.resumed_locked() > before || cnc_.state_locked() == "idle"; }, 30, "cycle start");
    }
    void progress(const acq::Progress& p) override {
        if (events_.progress) events_.progress(p);
    }
    void message(std::string_view text) override { tell(text); }

  private:
    void tell(std::string_view text) {
        if (events_.message) events_.message(text);
    }
    Linuxcnc& cnc_;
    device::SimulatedMachine& machine_;
    fs::path dir_;
    std::string label_;
    const LinuxcncLoopEvents& events_;
    int programs_ = 0;
    std::string part_program_;
};

/// Reads the FIFO halsampler writes, for as long as the loop runs a LinuxCNC.
class FifoReader {
  public:
    FifoReader(const fs::path& fifo, std::shared_ptr<device::TrajectoryFeed> feed) : feed_(std::move(feed)) {
        ::unlink(fifo.c_str());
        if (::mkfifo(fifo.c_str(), 0666) != 0)
            throw Error(ErrorCategory::failed, "cannot make the FIFO " + fifo.string() + ": " + std::strerror(errno));
        ::chmod(fifo.c_str(), 0666);  // halsampler runs as LinuxCNC's user
        // Read and write: the open does not wait for halsampler, and its end is no end of file.
        fd_ = ::open(fifo.c_str(), O_RDWR | O_CLOEXEC);
        if (fd_ < 0) throw Error(ErrorCategory::failed, "cannot open " + fifo.string() + ": " + std::strerror(errno));
        thread_ = std::thread([this] { feed_->read_lines(fd_, stop_); });
    }
    ~FifoReader() {
        stop_ = true;
        if (thread_.joinable()) thread_.join();
        ::close(fd_);
    }
    FifoReader(const FifoReader&) = delete;
    FifoReader& operator=(const FifoReader&) = delete;

  private:
    std::shared_ptr<device::TrajectoryFeed> feed_;
    int fd_ = -1;
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

struct Phase {
    std::int64_t session = 0;
    std::vector<acq::LocationResult> locations;
    std::uint64_t cycles = 0;
    std::optional<LoopCircle> circle;
};

/// The circular test `t` through LinuxCNC after an SSM: the table tilted and the tool at the first run's
/// stand (a positioning program), then the test's program as the circular procedure asks for it.
LoopCircle circle_through_linuxcnc(storage::Store& store, const acq::MachineFile& machine, const circ::TestSpec& t,
                                   double a_deg, PtyEmulator& emulator, Linuxcnc& cnc, LinuxcncOperator& op,
                                   const std::string& label) {
    constexpr double kDwell_s = 1.0;
    const auto ax = circ::plane_axis_index(t.plane);
    std::array<double, 3> stand = t.centre_mm;
    const double a0 = t.runs.front().start_deg * M_PI / 180.0;
    stand[static_cast<std::size_t>(ax[0])] += (t.radius_mm + t.feed_in_mm) * std::cos(a0);
    stand[static_cast<std::size_t>(ax[1])] += (t.radius_mm + t.feed_in_mm) * std::sin(a0);
    const auto& num = acq::nc_number;
    op.start("(ballbar " + label + ": the table to A" + num(a_deg) + ", the tool to the circular test's stand)\n" +
                 "G21 G90 G94 G17\nG0 Z" + num(stand[2]) + "\nG0 A" + num(a_deg) + " C0\nG0 X" + num(stand[0]) + " Y" +
                 num(stand[1]) + "\nM2\n",
             "positioning for the circular test");
    cnc.wait([&] { return cnc.state_locked() == "idle"; }, 120, "the positioning program's end");

    op.set_part_program(acq::circular_program(t, machine.dialect, kDwell_s));
    PreparedCircular prepared;
    prepared.test = t;
    prepared.dialect = machine.dialect;
    prepared.dwell_s = kDwell_s;
    prepared.session = create_circular_session(
        store, t, machine.dialect, kDwell_s, storage::SessionSource::emulator, "linuxcnc-loop",
        "ballbar demo --controller linuxcnc: circular test, " + label + ", table at A = " + num(a_deg) + "°",
        &machine.geometry);
    CircularMeasureOptions mo;
    mo.device_uri = "serial:" + emulator.path();
    mo.operator_name = "linuxcnc-loop";
    mo.notes = "ballbar demo --controller linuxcnc";
    mo.open_transport = [&emulator] { return device::open_transport("serial:" + emulator.path()); };
    const CircularMeasureResult run = measure_circular(store, prepared, op, mo);
    throw_unless_completed(run.summary, run.session_id, "");
    if (!run.stored) throw Error(ErrorCategory::failed, "the circular test (" + label + ") has no result");
    const circ::CircularResult& r = run.stored->result;
    LoopCircle c;
    c.phase = label;
    c.session = *prepared.session;
    c.g_um = r.bidirectional_um.value_or(0.0);
    c.radial_range_um = r.radial_max_um - r.radial_min_um;
    c.mean_radius_um = r.mean_radius_um;
    return c;
}

/// One SSM session through LinuxCNC with `kinematics` and the HAL lines `halcmds`.
Phase measure_through_linuxcnc(storage::Store& store, const acq::MachineFile& machine, const acq::Plan& plan,
                               const device::EmulatorConfig& emu_cfg, const fs::path& dir, const std::string& label,
                               const std::string& kinematics, const std::string& halcmds, bool compensating,
                               const std::optional<circ::TestSpec>& circle, const LinuxcncLoopEvents& events) {
    const fs::path cfg = dir / ("linuxcnc-" + label);
    fs::create_directories(cfg);
    ::chmod(dir.c_str(), 0755);
    ::chmod(cfg.c_str(), 0777);  // LinuxCNC's user writes its parameter file here
    write_text(cfg / "ballbar-loop.ini",
               replace_all(replace_all(lcnc_config::kIni, "@KINEMATICS@", kinematics), "@HALCMDS@", halcmds));
    write_text(cfg / "ballbar-loop.hal", lcnc_config::kHal);
    write_text(cfg / "loop.tbl", lcnc_config::kToolTable);
    write_text(cfg / "ballbar_display.py", lcnc_config::kDisplay, 0755);

    auto feed = std::make_shared<device::TrajectoryFeed>(0.001, 0.25);
    FifoReader fifo(cfg / "joints.fifo", feed);
    PtyEmulator emulator(emu_cfg, device::Pacing::RealTime);
    device::SimulatedMachine& m = emulator.emulator().machine();
    m.follow(feed);
    m.keep_history();

    Linuxcnc cnc(cfg, "ballbar-loop.ini", dir / ("linuxcnc-" + label + ".log"));
    cnc.wait([&] { return cnc.ready_locked(); }, 90, "machine on and homed");
    if (events.message) events.message("LinuxCNC is on and homed (" + label + "): " + kinematics);

    storage::NewSession ns;
    ns.machine = machine.geometry;
    ns.source = storage::SessionSource::emulator;
    ns.operator_name = "linuxcnc-loop";
    ns.procedure = "ssm-two-step";
    ns.notes = "ballbar demo --controller linuxcnc: " + label + " (" + kinematics + ")";
    storage::Instrument inst;
    inst.model = emu_cfg.instrument.model;
    inst.serial = emu_cfg.instrument.serial;
    inst.firmware = emu_cfg.instrument.firmware;
    inst.calibrated_length_mm = emu_cfg.instrument.calibrated_length_mm;
    ns.instrument = inst;
    Phase out;
    out.session = store.create_session(ns);
    store.start_session(out.session);
    store_plan(store, out.session, plan);

    LinuxcncOperator op(plan, cnc, m, cfg, label, events);
    acq::SessionSummary summary;
    {
        DeviceSource source([&emulator] { return device::open_transport("serial:" + emulator.path()); });
        StoreSink sink(store, out.session, plan);
        acq::Session session(plan, source, sink, op, {});
        summary = session.run();
        sink.finish(summary);
        store_bar_resolution(store, out.session, source, 0);
    }
    if (circle && summary.final_state == acq::State::Done) {
        if (events.message) events.message("the circular test through LinuxCNC (" + label + ")");
        out.circle = circle_through_linuxcnc(store, machine, *circle, kCircleA_deg, emulator, cnc, op, label);
    }
    cnc.stop();
    emulator.halt();
    out.cycles = feed->cycles();
    if (summary.final_state != acq::State::Done)
        throw Error(ErrorCategory::failed,
                    "the " + label + " session " + std::to_string(out.session) + " through LinuxCNC ended " +
                        std::string(storage::to_string(store.session(out.session).state)) + ": " + summary.reason);
    // With the nominal kinematics LinuxCNC puts the joints on the planned pose (halsampler's six
    // decimals); compensating, a correction of tens of µm and hundredths of a degree away from it.
    const TruthCheck tc = compensating
                              ? check_against_truth(store, out.session, emulator.emulator(), 0.2, kDegree * 0.1)
                              : check_against_truth(store, out.session, emulator.emulator(), 1e-4, 1e-6);
    if (tc.wrong_pose > 0)
        throw Error(ErrorCategory::failed,
                    "the " + label + " session " + std::to_string(out.session) + ": " + std::to_string(tc.wrong_pose) +
                        " points stored away from where LinuxCNC put the machine (first: " + tc.first_wrong + ")");
    for (const auto& r : store.results(out.session))
        if (r.kind == acq::kSsmResultKind) out.locations.push_back(acq::location_from_json(r.payload_json));
    return out;
}

/// "Y0A = -12.30 µm", "C0Y = 8.25\"" (angles in arcseconds at the operator's screen).
std::string param_text(ba::Param p, double value) {
    const ba::ParamInfo& info = ba::param_info(p);
    char buf[96];
    switch (info.unit) {
        case ba::ParamUnit::rad:
            std::snprintf(buf, sizeof buf, "%s = %.2f\"", std::string(info.name).c_str(),
                          value * 180.0 / M_PI * 3600.0);
            break;
        case ba::ParamUnit::mm_per_mm:
            std::snprintf(buf, sizeof buf, "%s = %.2f µm/m", std::string(info.name).c_str(), value * 1e6);
            break;
        default:
            std::snprintf(buf, sizeof buf, "%s = %.2f µm", std::string(info.name).c_str(), value * 1e3);
    }
    return buf;
}

void store_comparison(storage::Store& store, std::int64_t session, const std::string& metric,
                      const std::array<double, 3>& before_um, const std::array<double, 3>& after_um) {
    storage::CompensationRecord stored;
    stored.metric = metric;
    for (std::size_t k = 0; k < 3; ++k) stored.axes.push_back({std::string(1, "XYZ"[k]), before_um[k], after_um[k]});
    store.add_result(session, std::string(storage::kCompensationResultKind), storage::compensation_to_json(stored),
                     std::nullopt, "ballbar demo/1");
}

}  // namespace

double LinuxcncLoopResult::gain(int axis) const {
    const double a = rms_after_um[static_cast<std::size_t>(axis)];
    return a > 0 ? rms_before_um[static_cast<std::size_t>(axis)] / a : 0.0;
}

double LinuxcncLoopResult::third_gain(int axis) const {
    const double a = rms_third_um[static_cast<std::size_t>(axis)];
    return third_session != 0 && a > 0 ? rms_before_um[static_cast<std::size_t>(axis)] / a : 0.0;
}

std::string hidden_effect_refusal(std::string_view id) {
    const ba::Effect* e = ba::find_effect(id);
    if (!e) return "no such effect (docs/discovery.md lists them)";
    const std::string name(ba::param_info(e->param).name);
    const auto base = ba::rotary_params_for(ba::MachineType::TTTRR);
    if (std::find(base.begin(), base.end(), e->param) != base.end())
        return name + " is in the loop's model already: hide an effect outside it";
    if (e->param == ba::Param::bar_length || e->param == ba::Param::bar_kappa)
        return "an error of the bar, not of the machine: no compensation in the controller removes it";
    if (e->unit() == ba::ParamUnit::mm_per_h || e->unit() == ba::ParamUnit::per_K)
        return "a thermal effect: the loop's sessions last minutes and it would not show; hide one of the "
               "machine's geometry";
    return {};
}

double hidden_effect_size(ba::Param p) {
    switch (ba::param_info(p).unit) {
        case ba::ParamUnit::rad:
            return 40e-6;  // 8": a squareness or tilt a machine is set up within
        case ba::ParamUnit::mm_per_mm:
            return 40e-6;  // 40 µm/m: a ball screw's pitch error left uncompensated
        default:
            return 0.015;  // 15 µm: a tool length measured off
    }
}

std::string linuxcnc_loop_unavailable(const std::string& module_path) {
    if (::access("/usr/bin/linuxcnc", X_OK) != 0)
        return "LinuxCNC is not installed (scripts/install-deps.sh installs linuxcnc-uspace)";
    std::error_code ec;
    const auto st = fs::symlink_status(module_link(), ec);
    const bool installed = fs::exists(st) && !fs::is_symlink(st);
    if (installed) return {};
    if (module_path.empty())
        return module_link().string() + " is not installed (the ballbar package installs it; a build tree's " +
               "module is linked there by a run as root)";
    if (::access(module_path.c_str(), R_OK) != 0) return "the module " + module_path + " was not built";
    if (::geteuid() != 0)
        return "linking the build's module as " + module_link().string() + " needs root (or install the package)";
    return {};
}

acq::MachineFile loop_machine() {
    acq::MachineFile m = acq::seed_machine(ba::MachineType::TTTRR);
    m.geometry.name = "LinuxCNC loop (XYZAC)";
    // The simulator's machine: the A axis through (·, 20, 10), the C frame 110 mm below it and 20 mm
    // towards −Y (xyzac-trt-kins: rotation point (0, 0, −100), y-offset 20, z-offset 110).
    m.geometry.a_pivot_mm = ba::Vec3(0, 20, 10);
    m.geometry.c_offset_mm = ba::Vec3(0, -20, -110);
    m.geometry.tool_ball_mm = ba::Vec3::Zero();
    m.dialect = ba::NcDialect::LinuxCNC;
    m.feed_mm_min = 12000;
    m.travel[static_cast<std::size_t>(acq::Axis::A)] = {-30, 110};
    return m;
}

acq::PlanSpec loop_plan() {
    acq::PlanSpec s;
    s.bar_length_mm = 100;
    s.layout = ba::LayoutKind::CubeCorner;
    s.dwell_s = 1.0;
    s.capture.window_s = 0.25;
    s.answers.operator_name = "linuxcnc-loop";
    s.answers.on_point_failure = acq::PointFailureAction::Retry;
    const ba::Vec3 socket(-40, 30, 60);
    for (auto [a, c] : {std::pair{30.0, 0.0}, {20.0, 90.0}, {-20.0, 200.0}, {40.0, -120.0}})
        s.tests.push_back({socket, ba::deg_to_rad(a), ba::deg_to_rad(c), acq::TestKind::BothAxes, {}});
    return s;
}

circ::TestSpec loop_circle(const acq::MachineFile& machine, const acq::PlanSpec& plan, double a_deg) {
    circ::TestSpec t;
    t.plane = circ::Plane::XY;
    t.radius_mm = plan.bar_length_mm;
    t.feed_mm_min = 3000;  // 14 s a run; the feed-in at full feed after LinuxCNC's 12 ms ramp
    t.feed_in_mm = 0.9;    // within the bar's ±1 mm
    // The tool ball on the socket with the table tilted: the circle's centre in machine coordinates.
    ba::Pose rotary;
    rotary.A_rad = ba::deg_to_rad(a_deg);
    const ba::Vec3 socket = plan.tests.empty() ? ba::Vec3::Zero() : plan.tests.front().socket_mm;
    const ba::Pose c =
        ba::command_for_tool_ball(machine.geometry, rotary, ba::nominal_table_ball(machine.geometry, rotary, socket));
    t.centre_mm = {c.X_mm, c.Y_mm, c.Z_mm};
    // The clockwise run starts where the counter-clockwise one ended (400° on): its feed-in is radial.
    t.runs = {{circ::Direction::Ccw, 0.0, 20.0, 360.0}, {circ::Direction::Cw, 40.0, 20.0, 360.0}};
    return t;
}

ba::ErrorParams loop_errors(int set) {
    ba::ErrorParams e = acq::demo_errors(ba::MachineType::TTTRR);
    e[ba::Param::tool_length] = 0;  // the loop's model is the rotary axes' locations (identify's default)
    if (set == 0) return e;
    std::mt19937_64 rng(static_cast<std::uint64_t>(set));
    std::uniform_real_distribution<double> u(-1.5, 1.5);
    for (const ba::Param p : ba::rotary_params_for(ba::MachineType::TTTRR)) {
        const bool angle = ba::param_info(p).unit == ba::ParamUnit::rad;
        e[p] = u(rng) * (angle ? 30e-6 : 0.02);  // 30 µrad (6"), 20 µm
    }
    return e;
}

LinuxcncLoopResult run_linuxcnc_loop(storage::Store& store, const LinuxcncLoopOptions& o,
                                     const LinuxcncLoopEvents& events) {
    if (const std::string why = linuxcnc_loop_unavailable(o.module_path); !why.empty())
        throw Error(ErrorCategory::device, "LinuxCNC cannot run the loop here: " + why);
    if (const std::string why = linuxcnc_in_the_way(); !why.empty())
        throw Error(ErrorCategory::device, "LinuxCNC cannot run the loop now: " + why);
    LinuxcncLoopResult out;
    fs::path dir;
    if (o.work_dir.empty()) {
        std::string tmpl = (fs::temp_directory_path() / "ballbar-linuxcnc-XXXXXX").string();
        if (!::mkdtemp(tmpl.data())) throw Error(ErrorCategory::failed, "cannot make a work directory");
        dir = tmpl;
    } else {
        dir = o.work_dir;
        std::error_code ec;
        if (fs::exists(fs::symlink_status(dir, ec)))
            throw Error(ErrorCategory::bad_input,
                        "--work-dir " + dir.string() + " exists: the loop writes into a new directory only");
        fs::create_directories(dir);
    }
    out.work_dir = dir.string();
    ::chmod(dir.c_str(), 0755);
    if (const std::string why = unreachable_by_rtapi(dir); !why.empty())
        throw Error(ErrorCategory::bad_input, "LinuxCNC cannot use the work directory " + dir.string() + ": " + why);
    // The build's module, where LinuxCNC loads modules from: a link this loop makes and re-points, never
    // a file it did not make (an installed module is used as it is).
    if (!o.module_path.empty()) {
        std::error_code ec;
        const auto st = fs::symlink_status(module_link(), ec);
        if (!fs::exists(st) || fs::is_symlink(st)) {
            const fs::path copy = dir / "ballbarkins.so";
            fs::copy_file(o.module_path, copy, fs::copy_options::overwrite_existing);
            ::chmod(copy.c_str(), 0644);
            if (fs::is_symlink(st)) fs::remove(module_link());
            fs::create_symlink(copy, module_link());
        }
    }

    const acq::MachineFile machine = loop_machine();
    acq::PlanSpec spec = o.plan.value_or(loop_plan());
    const acq::Plan plan = acq::make_plan(machine, spec);
    std::optional<circ::TestSpec> circle;
    if (o.circle) circle = loop_circle(machine, spec, kCircleA_deg);

    device::EmulatorConfig cfg;
    cfg.seed = o.seed;
    cfg.instrument.calibrated_length_mm = spec.bar_length_mm;
    cfg.instrument.noise_um = 0.1;
    cfg.instrument.serial = "EMU" + std::to_string(10000 + ::getpid() % 90000);
    cfg.machine.geometry = machine.geometry;
    cfg.machine.errors = o.errors.value_or(loop_errors());
    cfg.machine.socket_mm = plan.points.front().socket_mm;
    cfg.machine.start = {};  // LinuxCNC's home: every joint at 0

    // 1. The nominal kinematics: ballbarkins with a model of no errors, its correction off.
    storage::ErrorModel nominal;
    nominal.machine = machine.geometry;
    const fs::path nominal_path = dir / "nominal.model.json";
    write_text(nominal_path, storage::model_to_json(nominal));
    if (events.message) events.message("1. the SSM through LinuxCNC, ballbarkins disabled (the nominal kinematics)");
    const Phase before = measure_through_linuxcnc(store, machine, plan, cfg, dir, "before",
                                                  "ballbarkins model=" + nominal_path.string() + " sparm=identityfirst",
                                                  "HALCMD = setp ballbarkins.enable 0\n", false, circle, events);
    out.before_session = before.session;

    // 2. Identification from that session.
    if (events.message) events.message("2. identification from session " + std::to_string(before.session));
    IdentifyOptions io;
    io.model_name = "linuxcnc-loop";
    const std::vector<std::string> inputs{std::to_string(before.session)};
    IdentifyResult id = identify(read_inputs(inputs, [&]() -> storage::Store& { return store; }), io,
                                 [&]() -> storage::Store& { return store; });
    if (!id.fit.converged) throw Error(ErrorCategory::failed, "the identification did not converge");
    for (const auto& e : id.fit.estimates)
        if (e.param && e.observable) out.identified.push_back(param_text(*e.param, e.estimate));

    // 3. The model in ballbarkins, compensation on; 4. the same SSM again.
    const std::string model_text = storage::model_to_json(id.model);
    const fs::path model_path = dir / "identified.model.json";
    write_text(model_path, model_text);
    out.model_path = model_path.string();
    out.model_hash = fnv1a(model_text);
    if (events.message) events.message("3. the identified model in ballbarkins, compensation on: " + out.model_path);
    const Phase after = measure_through_linuxcnc(store, machine, plan, cfg, dir, "after",
                                                 "ballbarkins model=" + model_path.string() + " sparm=identityfirst",
                                                 "", true, circle, events);
    out.after_session = after.session;
    out.servo_cycles = before.cycles + after.cycles;
    for (const Phase* p : {&before, &after})
        if (p->circle) out.circles.push_back(*p->circle);

    // 6. What the model misses: the discovery workflow on the first session (measured with the nominal
    // kinematics, so its readings are the machine's own); the extended model back into ballbarkins.
    std::optional<Phase> third;
    if (o.discover) {
        if (events.message)
            events.message("5. the discovery workflow on session " + std::to_string(before.session) +
                           ": what the identified model misses");
        DiscoverOptions dopt;
        dopt.save_model = "linuxcnc-loop-discovered";
        const DiscoverResult d = discover(read_inputs(inputs, [&]() -> storage::Store& { return store; }), dopt,
                                          [&]() -> storage::Store& { return store; });
        out.discovery_ran = true;
        for (const auto& step : d.result.steps) {
            if (step.withdrawn || !step.effect) continue;
            const std::string iso = step.effect->iso.empty() ? "" : " (" + std::string(step.effect->iso) + ")";
            std::string value = param_text(step.effect->param, step.estimate);
            value = value.substr(value.find(" = "));
            out.discovered.push_back(std::string(step.effect->id) + iso + value);
        }
        for (const auto& t : d.result.learned_terms) out.discovered.push_back("an empirical term " + t.term.name());
        out.discovery_verdict = d.result.verdict.text;
        if (!out.discovered.empty() && d.stored) {
            const fs::path ext_path = dir / "extended.model.json";
            write_text(ext_path, d.stored->params_json);
            out.extended_model_path = ext_path.string();
            if (events.message)
                events.message("6. the extended model in ballbarkins, the same SSM a third time: " +
                               out.extended_model_path);
            third = measure_through_linuxcnc(store, machine, plan, cfg, dir, "extended",
                                             "ballbarkins model=" + ext_path.string() + " sparm=identityfirst", "",
                                             true, circle, events);
            out.third_session = third->session;
            out.servo_cycles += third->cycles;
            if (third->circle) out.circles.push_back(*third->circle);
        } else if (events.message) {
            events.message("   the discovery named nothing the model misses: no third measurement");
        }
    }

    // 5. Each location's total position error before and after (and with the extended model), and the
    // machine's part of it: e less the set-up offset that best explains each measurement's e.
    const std::vector<acq::TrueTest> truth = acq::true_values(plan, cfg.machine.errors);
    if (!id.model.sockets.empty()) out.identified_setup_mm = id.model.sockets.front().offset_mm;
    std::vector<ba::Mat3> turn;  // the table's rotation at each location (the socket turns with it)
    std::vector<ba::Vec3> eb, ea, et;
    for (const auto& b : before.locations) {
        const auto same = [&](const acq::LocationResult& x) { return x.test == b.test && x.step == b.step; };
        const auto a = std::find_if(after.locations.begin(), after.locations.end(), same);
        if (a == after.locations.end()) continue;
        LoopLocation l;
        l.test = b.test, l.step = b.step;
        l.before_mm = b.ssm.exact_mm, l.after_mm = a->ssm.exact_mm;
        if (third) {
            const auto t = std::find_if(third->locations.begin(), third->locations.end(), same);
            if (t == third->locations.end()) continue;
            l.third_mm = t->ssm.exact_mm;
            et.push_back(*l.third_mm);
        }
        const acq::TrueTest& t = truth.at(static_cast<std::size_t>(b.test));
        l.true_before_mm = b.step == 1 ? t.e1_mm : t.e2_mm;
        const acq::TestSpec& ts = plan.spec.tests.at(static_cast<std::size_t>(b.test));
        turn.push_back(b.step == 1 ? ba::Mat3::Identity()
                                   : ba::Mat3(Eigen::AngleAxisd(ts.first_rad, ba::Vec3::UnitX()) *
                                              Eigen::AngleAxisd(ts.second_rad, ba::Vec3::UnitZ())));
        eb.push_back(l.before_mm), ea.push_back(l.after_mm);
        out.locations.push_back(l);
    }
    // min Σ|e_i + R_i·s|² with R_i orthonormal: s = −mean(R_iᵀ·e_i).
    const auto setup_of = [&](const std::vector<ba::Vec3>& e) {
        ba::Vec3 s = ba::Vec3::Zero();
        for (std::size_t i = 0; i < e.size(); ++i) s -= turn[i].transpose() * e[i];
        return e.empty() ? s : ba::Vec3(s / static_cast<double>(e.size()));
    };
    out.setup_before_mm = setup_of(eb), out.setup_after_mm = setup_of(ea);
    if (third) out.setup_third_mm = setup_of(et);
    std::array<double, 3> sb{}, sa{}, st{}, rb{}, ra{};
    for (std::size_t i = 0; i < out.locations.size(); ++i) {
        LoopLocation& l = out.locations[i];
        l.machine_before_mm = l.before_mm + turn[i] * out.setup_before_mm;
        l.machine_after_mm = l.after_mm + turn[i] * out.setup_after_mm;
        if (l.third_mm) l.machine_third_mm = *l.third_mm + turn[i] * out.setup_third_mm;
        for (std::size_t k = 0; k < 3; ++k) {
            const auto j = static_cast<Eigen::Index>(k);
            sb[k] += std::pow(l.machine_before_mm[j], 2), sa[k] += std::pow(l.machine_after_mm[j], 2);
            if (l.machine_third_mm) st[k] += std::pow((*l.machine_third_mm)[j], 2);
            rb[k] += std::pow(l.before_mm[j], 2), ra[k] += std::pow(l.after_mm[j], 2);
        }
    }
    const double n = static_cast<double>(std::max<std::size_t>(out.locations.size(), 1));
    for (std::size_t k = 0; k < 3; ++k) {
        out.rms_before_um[k] = 1e3 * std::sqrt(sb[k] / n), out.rms_after_um[k] = 1e3 * std::sqrt(sa[k] / n);
        out.rms_raw_before_um[k] = 1e3 * std::sqrt(rb[k] / n), out.rms_raw_after_um[k] = 1e3 * std::sqrt(ra[k] / n);
        if (third) out.rms_third_um[k] = 1e3 * std::sqrt(st[k] / n);
    }
    // Stored with the later sessions: their reports have the before/after page.
    const std::string over =
        "RMS machine position error (SSM's e less the socket set-up offset that best explains it) over "
        "the plan's " +
        std::to_string(out.locations.size()) + " SSM locations, measured through LinuxCNC: session " +
        std::to_string(out.before_session) + " with ballbarkins disabled (nominal kinematics), ";
    store_comparison(
        store, out.after_session,
        over + "session " + std::to_string(out.after_session) + " with the model identified from it in ballbarkins",
        out.rms_before_um, out.rms_after_um);
    if (third)
        store_comparison(store, out.third_session,
                         over + "session " + std::to_string(out.third_session) +
                             " with the model the discovery extended in ballbarkins",
                         out.rms_before_um, out.rms_third_um);
    return out;
}

}  // namespace ballbar::workflow
