// SPDX-License-Identifier: MIT
// Runs LinuxCNC's headless simulator (tests/linuxcnc/sim/) on one program with a given kinematics
// line and reads what its sampler recorded every servo cycle. LinuxCNC runs one instance per machine
// (a global lock, fixed shared-memory keys): the tests that use this run one at a time (a ctest
// RESOURCE_LOCK, tests/CMakeLists.txt).
//
// LinuxCNC 2.9 as Debian packages it loads modules only from /usr/lib/linuxcnc/modules/NAME.so; a copy
// of the build's module in the run's directory is linked there as `ballbarkins.so` (a symbolic link the
// harness makes and re-points; it never replaces a file it did not make: with the ballbar package
// installed the tests skip). rtapi_app refuses to
// run with a real uid of 0 unless told an unprivileged one (RTAPI_UID), which must be able to read the model and to
// create rtapi_app's socket (RTAPI_FIFO_PATH names the socket itself, in a directory that uid owns).
#pragma once

#include <sys/shm.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "../scratch_dir.hpp"

namespace ballbar::test::lcnc {

namespace fs = std::filesystem;

inline constexpr const char* kModuleDir = "/usr/lib/linuxcnc/modules";
// The module's HAL component is "ballbarkins", and halcmd's loadrt waits for a component named as the
// module file: the build's module is linked under the installed name.
inline constexpr const char* kBuildModuleName = "ballbarkins";
inline constexpr unsigned kRtapiUid = 65534;  // nobody

/// One servo cycle: joints 0-4 and the axes' commands X Y Z A C (mm, degrees), the kinematics type
/// (motion.switchkins-type), the program line.
struct Sample {
    std::array<double, 5> joints{}, world{};
    double kinstype = 0;
    int line = 0;
};

struct SimRun {
    int status = -1;
    std::string log;
    std::vector<Sample> samples;
};

/// Why the simulator cannot run here (empty when it can): no LinuxCNC, no module, no root.
inline std::string unavailable() {
    if (::access("/usr/bin/linuxcnc", X_OK) != 0)
        return "LinuxCNC is not installed (scripts/install-deps.sh installs linuxcnc-uspace)";
#ifndef BALLBAR_KINS_MODULE
    return "the ballbarkins module was not built (LinuxCNC's development files were absent at configure time)";
#else
    if (::geteuid() != 0) return "the LinuxCNC tests link the module into /usr/lib/linuxcnc/modules: run them as root";
    const fs::path link = fs::path(kModuleDir) / (std::string(kBuildModuleName) + ".so");
    std::error_code ec;
    if (fs::exists(fs::symlink_status(link, ec)) && !fs::is_symlink(fs::symlink_status(link, ec)))
        return link.string() + " is installed (the ballbar package?), not a link this test made: not replaced";
    return {};
#endif
}

/// Frees the shared memory a killed LinuxCNC left (a test timed out, a CI machine reused): LinuxCNC's
/// System V keys (HAL, RTAPI, motion, the NML buffers, the samplers), attached by no process, while no
/// LinuxCNC runs; a later LinuxCNC fails on a leftover of another size ("shmget ... Invalid argument").
/// The tests run one LinuxCNC at a time (their lock), so what is left is a test's. `ballbar demo
/// --controller linuxcnc` refuses, naming the keys, instead: it frees nothing it did not make.
inline void free_orphaned_shm() {
    if (std::system("pgrep -x rtapi_app > /dev/null || pgrep -x milltask > /dev/null || "
                    "pgrep -x linuxcncsvr > /dev/null") == 0)
        return;
    std::ifstream shm("/proc/sysvipc/shm");
    std::string line;
    std::getline(shm, line);  // key shmid perms size cpid lpid nattch ...
    while (std::getline(shm, line)) {
        std::istringstream f(line);
        long key = 0, shmid = 0, perms = 0, size = 0, cpid = 0, lpid = 0, nattch = -1;
        if (!(f >> key >> shmid >> perms >> size >> cpid >> lpid >> nattch) || nattch != 0) continue;
        const bool lcnc = key == 0x48414c32 || key == 0x48484c34 || key == 100 || (key >= 1001 && key <= 1005) ||
                          (key >= 0x48534130 && key <= 0x48534137) || (key >= 0x48535430 && key <= 0x48535437);
        if (lcnc && ::shmctl(static_cast<int>(shmid), IPC_RMID, nullptr) == 0)
            std::fprintf(stderr, "freed a killed LinuxCNC's shared memory: key 0x%08lx, %ld bytes\n", key, size);
    }
}

/// Points /usr/lib/linuxcnc/modules/ballbarkins.so at a copy of the build's module in `dir`: rtapi_app
/// reads it there whatever the permissions of the build tree (a clean clone may sit in a private
/// directory).
inline void link_module(const fs::path& dir) {
#ifdef BALLBAR_KINS_MODULE
    const fs::path copy = dir / "ballbarkins.so";
    fs::copy_file(BALLBAR_KINS_MODULE, copy, fs::copy_options::overwrite_existing);
    ::chmod(copy.c_str(), 0644);
    const fs::path link = fs::path(kModuleDir) / (std::string(kBuildModuleName) + ".so");
    std::error_code ec;
    if (fs::is_symlink(fs::symlink_status(link, ec))) fs::remove(link);
    fs::create_symlink(copy, link);
#else
    (void)dir;
#endif
}

inline std::string read_text(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

inline std::string replace_all(std::string s, const std::string& from, const std::string& to) {
    for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
        s.replace(at, from.size(), to);
    return s;
}

/// A long CAM program run faster than written: the feed override (LinuxCNC caps it at [DISPLAY]
/// MAX_FEED_OVERRIDE, 1 unless set: the simulator's INI sets 1000) and every velocity and acceleration
/// limit multiplied by `limits_scale` (the servo loop is perfect: nothing follows but numbers).
struct Speedup {
    double feed_override = 1;
    double limits_scale = 1;
};

/// The INI's MAX_..._VELOCITY and MAX_..._ACCELERATION values times `scale`.
inline std::string scale_limits(const std::string& ini, double scale) {
    if (scale == 1) return ini;
    std::istringstream in(ini);
    std::string out, line;
    while (std::getline(in, line)) {
        const auto eq = line.find(" = ");
        const bool limit = line.rfind("MAX_", 0) == 0 &&
                           (line.find("VELOCITY") < eq || line.find("ACCELERATION") < eq) && eq != std::string::npos;
        if (limit) line = line.substr(0, eq + 3) + std::to_string(std::stod(line.substr(eq + 3)) * scale);
        out += line + "\n";
    }
    return out;
}

/// Runs `program` (its text) with `kinematics` (the [KINS]KINEMATICS line) and extra HALCMD lines.
/// The directory `dir` receives the configuration, the model files the caller wrote stay readable.
inline SimRun run_sim(const ScratchDir& dir, const std::string& kinematics, const std::string& program,
                      const std::vector<std::string>& halcmds = {}, Speedup speedup = {}) {
    ::chmod(dir.path.c_str(), 0755);  // rtapi_app runs as RTAPI_UID: it reads the module and the model here
    free_orphaned_shm();
    link_module(dir.path);
    const fs::path sim = fs::path(BALLBAR_LINUXCNC_SIM_DIR);
    const fs::path cfg = dir.path / "cfg";
    fs::create_directories(cfg / "remap_subs");
    for (const char* f :
         {"ballbar.hal", "run_program.py", "tool.tbl", "remap_subs/428remap.ngc", "remap_subs/429remap.ngc"})
        fs::copy_file(sim / f, cfg / f, fs::copy_options::overwrite_existing);
    std::string hal;
    for (const auto& h : halcmds) hal += "HALCMD = " + h + "\n";
    std::string ini = read_text(sim / "ballbar.ini");
    ini = replace_all(ini, "@KINEMATICS@", kinematics);
    ini = replace_all(ini, "@HALCMDS@", hal);
    ini = scale_limits(ini, speedup.limits_scale);
    std::ofstream(cfg / "ballbar.ini") << ini;
    std::ofstream(cfg / "program.ngc") << program;
    // ... and creates its socket in a directory it owns.
    const fs::path fifo = dir.path / "rtapi_fifo";
    fs::create_directories(fifo);
    if (::chown(fifo.c_str(), kRtapiUid, static_cast<gid_t>(-1)) != 0) {
    }
    const std::string cmd = "cd '" + cfg.string() + "' && RTAPI_UID=" + std::to_string(kRtapiUid) +
                            " RTAPI_FIFO_PATH='" + (fifo / "socket").string() +
                            "' BALLBAR_FEED_OVERRIDE=" + std::to_string(speedup.feed_override) + " BALLBAR_PROGRAM='" +
                            (cfg / "program.ngc").string() + "' timeout 180 linuxcnc -r ballbar.ini > '" +
                            (dir.path / "linuxcnc.log").string() + "' 2>&1";
    SimRun run;
    const int rc = std::system(cmd.c_str());
    run.status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
    // `linuxcnc` returns before rtapi_app and milltask have gone: the next run must wait for them.
    for (int i = 0; i < 200; ++i) {
        if (std::system("pgrep -x rtapi_app > /dev/null || pgrep -x milltask > /dev/null") != 0) break;
        ::usleep(50'000);
    }
    run.log = read_text(dir.path / "linuxcnc.log");
    std::ifstream in(cfg / "samples.txt");
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream f(line);
        long n = 0;
        Sample s;
        if (!(f >> n)) continue;
        for (double& j : s.joints) f >> j;
        for (double& w : s.world) f >> w;
        f >> s.kinstype >> s.line;
        if (f) run.samples.push_back(s);
    }
    return run;
}

/// The machine at rest after each move. LinuxCNC 2.9's motion.program-line is the move's line while it
/// moves and 0 between moves (a G4 dwell included); the joint commands lag the axis commands by two
/// servo cycles; the axis commands of the next move start a cycle before its line shows, and an M428
/// or M429 after the dwell changes the kinematics type (and the world position with it) late in the
/// run. So the sample taken is a third into each run of 0 that follows a move: in the dwell, at
/// least 10 cycles after the move ended (the dwells here are 100 cycles).
inline std::vector<Sample> at_rest(const SimRun& run) {
    constexpr std::size_t kShortest = 30;  // cycles: a rest, not a pause between blended moves
    std::vector<Sample> out;
    bool after_move = false;
    std::size_t run_start = 0;
    for (std::size_t i = 0; i < run.samples.size(); ++i) {
        if (run.samples[i].line != 0) {
            after_move = true;
            run_start = i + 1;
            continue;
        }
        const bool last_of_run = i + 1 == run.samples.size() || run.samples[i + 1].line != 0;
        if (after_move && last_of_run && i + 1 >= run_start + kShortest) {
            out.push_back(run.samples[run_start + (i + 1 - run_start) / 3]);
            after_move = false;
        }
    }
    return out;
}

}  // namespace ballbar::test::lcnc
