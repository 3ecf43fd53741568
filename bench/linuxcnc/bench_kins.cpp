// SPDX-License-Identifier: MIT
// The cost of ballbarkins's kinematics per servo cycle (docs/linuxcnc.md, "Speed"): the module as
// built (ballbarkins.so) and LinuxCNC's own xyzac-trt-kins.so, both loaded into this program and
// timed in the same run. The modules are real LinuxCNC modules: they need HAL and RTAPI, which this
// program provides as a stand-in (pins are plain memory; messages go to stderr), exported to them.
//
// usage: bench_kins [Google Benchmark flags]   (needs /usr/lib/linuxcnc/modules/xyzac-trt-kins.so)
#include <benchmark/benchmark.h>
#include <dlfcn.h>
#include <unistd.h>

#include <array>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "emcpos.h"
#include "hal.h"
#include "rtapi.h"
extern "C" {
#include "kinematics.h"
}

namespace {

// Every pin a module creates, by name; 16 bytes each, enough for any HAL type.
std::map<std::string, std::unique_ptr<double[]>>& pin_memory() {
    static std::map<std::string, std::unique_ptr<double[]>> pins;
    return pins;
}

void* new_pin(const std::string& name) {
    auto& slot = pin_memory()[name];
    slot = std::make_unique<double[]>(2);
    return slot.get();
}

std::string format(const char* fmt, va_list ap) {
    char buf[256];
    std::vsnprintf(buf, sizeof buf, fmt, ap);
    return buf;
}

template <class T>
void set_pin(const std::string& name, T value) {
    const auto it = pin_memory().find(name);
    if (it == pin_memory().end()) throw std::runtime_error("no pin " + name);
    *reinterpret_cast<T*>(it->second.get()) = value;
}

}  // namespace

// The HAL and RTAPI the modules call at load (nothing of it in their servo-cycle path).
extern "C" {
int hal_init(const char*) {
    return 1;
}
int hal_exit(int) {
    return 0;
}
int hal_ready(int) {
    return 0;
}
void* hal_malloc(long int size) {
    return std::calloc(1, static_cast<std::size_t>(size));
}
int hal_pin_bit_new(const char* name, hal_pin_dir_t, hal_bit_t** p, int) {
    *p = static_cast<hal_bit_t*>(new_pin(name));
    return 0;
}
int hal_pin_s32_new(const char* name, hal_pin_dir_t, hal_s32_t** p, int) {
    *p = static_cast<hal_s32_t*>(new_pin(name));
    return 0;
}
#define BALLBAR_PIN_NEWF(kind, type)                                                \
    int hal_pin_##kind##_newf(hal_pin_dir_t, type** p, int, const char* fmt, ...) { \
        va_list ap;                                                                 \
        va_start(ap, fmt);                                                          \
        *p = static_cast<type*>(new_pin(format(fmt, ap)));                          \
        va_end(ap);                                                                 \
        return 0;                                                                   \
    }
BALLBAR_PIN_NEWF(bit, hal_bit_t)
BALLBAR_PIN_NEWF(float, hal_float_t)
BALLBAR_PIN_NEWF(u32, hal_u32_t)
void rtapi_print(const char* fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    std::fputs(format(fmt, ap).c_str(), stderr);
    va_end(ap);
}
void rtapi_print_msg(msg_level_t, const char* fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    std::fputs(format(fmt, ap).c_str(), stderr);
    va_end(ap);
}
}

namespace {

using Inverse = int (*)(const EmcPose*, double*, const KINEMATICS_INVERSE_FLAGS*, KINEMATICS_FORWARD_FLAGS*);
using Forward = int (*)(const double*, EmcPose*, const KINEMATICS_FORWARD_FLAGS*, KINEMATICS_INVERSE_FLAGS*);

struct Module {
    Inverse inverse = nullptr;
    Forward forward = nullptr;
};

// Loads a module as rtapi_app does: its string parameters set through rtapi_info_address_NAME,
// then rtapi_app_main().
Module load(const std::string& path, const std::map<std::string, std::string>& params) {
    void* h = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!h) throw std::runtime_error(std::string("cannot load ") + path + ": " + dlerror());
    static std::vector<std::string> values;  // the parameters' strings live as long as the modules
    values.reserve(16);
    for (const auto& [name, value] : params) {
        // rtapi_info_address_NAME holds the address of the module's `char* NAME`.
        auto* info = static_cast<char***>(dlsym(h, ("rtapi_info_address_" + name).c_str()));
        if (!info) throw std::runtime_error(path + " has no parameter " + name);
        values.push_back(value);
        **info = values.back().data();
    }
    auto* main = reinterpret_cast<int (*)()>(dlsym(h, "rtapi_app_main"));
    if (!main || main() != 0) throw std::runtime_error(path + ": rtapi_app_main failed");
    return {reinterpret_cast<Inverse>(dlsym(h, "kinematicsInverse")),
            reinterpret_cast<Forward>(dlsym(h, "kinematicsForward"))};
}

const char* const kModel = R"({"format":"ballbar-model/1","machine":{"type":"TTTRR","name":"bench",
 "a_pivot_mm":[0,20,10],"c_offset_mm":[0,-20,-110],"tool_ball_mm":[0,0,0]},
 "params":{"Y0A":0.025,"Z0A":-0.018,"B0A":4e-5,"C0A":-3e-5,"X0C":0.035,"Y0C":-0.022,"A0C":5e-5,"B0C":-3.5e-5,
 "A_zero":2e-5,"C_zero":-3e-5,"EXX":8e-6,"EYY":-6e-6,"C0Y":1e-5}})";

struct Modules {
    Module ours, stock;
    Modules() {
        char dir[] = "/tmp/ballbar-bench-kins-XXXXXX";
        if (!mkdtemp(dir)) throw std::runtime_error("mkdtemp failed");
        const std::string model = std::string(dir) + "/model.json";
        std::FILE* f = std::fopen(model.c_str(), "w");
        if (!f) throw std::runtime_error("cannot write " + model);
        std::fputs(kModel, f);
        std::fclose(f);
        ours = load(BALLBAR_KINS_MODULE, {{"model", model}});
        std::remove(model.c_str());
        rmdir(dir);
        stock = load("/usr/lib/linuxcnc/modules/xyzac-trt-kins.so", {{"coordinates", "XYZAC"}});
        set_pin("xyzac-trt-kins.z-rot-point", -100.0);
        set_pin("xyzac-trt-kins.y-offset", 20.0);
        set_pin("xyzac-trt-kins.z-offset", 110.0);
        set_pin("ballbarkins.tool-offset", 0.0);
    }
};

Modules& modules() {
    static Modules m;
    return m;
}

// A program's worth of poses (TCP type, the default of both modules).
std::vector<EmcPose> poses() {
    std::vector<EmcPose> out(1024);
    std::srand(1);
    for (EmcPose& p : out) {
        p = EmcPose{};
        p.tran.x = std::rand() % 30000 / 100.0 - 150;
        p.tran.y = std::rand() % 30000 / 100.0 - 150;
        p.tran.z = std::rand() % 30000 / 100.0 - 150;
        p.a = std::rand() % 18000 / 100.0 - 90;
        p.c = std::rand() % 72000 / 100.0 - 360;
    }
    return out;
}

void inverse(benchmark::State& state, Inverse f) {
    const auto ps = poses();
    double joints[9] = {};
    std::size_t i = 0;
    for (auto _ : state) {
        f(&ps[i++ & 1023], joints, nullptr, nullptr);
        benchmark::DoNotOptimize(joints);
    }
    state.SetItemsProcessed(state.iterations());
}

void forward(benchmark::State& state, Forward f) {
    const auto ps = poses();
    std::vector<std::array<double, 9>> js(ps.size());
    for (std::size_t k = 0; k < ps.size(); ++k) modules().ours.inverse(&ps[k], js[k].data(), nullptr, nullptr);
    EmcPose w{};
    std::size_t i = 0;
    for (auto _ : state) {
        f(js[i++ & 1023].data(), &w, nullptr, nullptr);
        benchmark::DoNotOptimize(w);
    }
    state.SetItemsProcessed(state.iterations());
}

void BM_BallbarkinsInverse(benchmark::State& s) {
    inverse(s, modules().ours.inverse);
}
void BM_XyzacTrtKinsInverse(benchmark::State& s) {
    inverse(s, modules().stock.inverse);
}
void BM_BallbarkinsForward(benchmark::State& s) {
    forward(s, modules().ours.forward);
}
void BM_XyzacTrtKinsForward(benchmark::State& s) {
    forward(s, modules().stock.forward);
}
BENCHMARK(BM_BallbarkinsInverse);
BENCHMARK(BM_XyzacTrtKinsInverse);
BENCHMARK(BM_BallbarkinsForward);
BENCHMARK(BM_XyzacTrtKinsForward);

}  // namespace

BENCHMARK_MAIN();
