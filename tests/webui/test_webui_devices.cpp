// SPDX-License-Identifier: MIT
// `ballbar serve` on instruments as the CLI reaches them: the circular test on the ball-bar protocol of
// `ballbar emulate --pty` in another process (the part program downloaded from the page and loaded on
// the emulated controller, the live reading with the bar's range, a stop, the resume from the page), a
// digital gauge refused for a feed it cannot follow, a demo whose instrument is lost and comes back, and
// `ballbar serve --demo` as a process, ended by SIGTERM.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <thread>

#include "../scratch_dir.hpp"
#include "ballbar/storage/store.hpp"
#include "webui_client.hpp"

namespace {

using json = nlohmann::json;
using namespace ballbar::test::webui;
using namespace std::chrono_literals;

/// The emulated machine and bar of `emulate --pty`: 4 µm of X backlash, 40 µm/m of XY squareness; the
/// machine runs the program in `program` at each cycle start (the operator loaded it on the controller).
std::string emulator_config(const ballbar::test::ScratchDir& dir, const std::string& program) {
    const std::string path = dir.file("emu.json");
    std::ofstream(path) << R"({
      "instrument": {"calibrated_length_mm": 100, "noise_um": 0.15},
      "machine": {"start": {"X_mm": 100.8, "Y_mm": 0, "Z_mm": 0}},
      "program": {"file": ")"
                        << program << R"(", "dialect": "linuxcnc"},
      "continuous": {"servo_lag_ms": {"X": 6, "Y": 4}, "backlash_um": {"X": 4, "Y": -2.5},
                     "squareness_um_per_m": {"XY": 40}}
    })";
    return path;
}

/// Answers the circular measurement's questions as the operator at the page: at "run the part program"
/// the program is downloaded from the page and loaded on the controller (written where the emulated
/// machine reads it), then cycle start. Returns when `until` holds for the state (polled every 10 ms),
/// or the procedure ended.
template <class Until>
json operate(httplib::Client& c, const std::string& program_file, int& programs_run, Until until) {
    std::uint64_t answered = 0;
    const auto give_up = std::chrono::steady_clock::now() + 180s;
    while (std::chrono::steady_clock::now() < give_up) {
        json state = get_json(c, "/api/procedure");
        if (!state["running"].get<bool>() || until(state)) return state;
        const json& q = state["question"];
        if (q.is_object() && q["id"].get<std::uint64_t>() != answered) {
            if (q["what"] == "run-part-program" || q["what"] == "run-program") {
                auto r = c.Get("/api/procedure/program");
                if (!r || r->status != 200) throw std::runtime_error("no program to download");
                std::ofstream(program_file) << r->body;
                ++programs_run;
            }
            answered = q["id"].get<std::uint64_t>();
            answer(c, answered);
        }
        std::this_thread::sleep_for(10ms);
    }
    throw std::runtime_error("the procedure did not end within 3 minutes");
}

/// The first "live" event of the page's stream while a procedure runs.
json first_live_reading(int port) {
    httplib::Client c("127.0.0.1", port);
    c.set_read_timeout(120, 0);
    std::string buf;
    json live;
    c.Get("/api/events?client=watcher", [&](const char* d, std::size_t n) {
        buf.append(d, n);
        const auto at = buf.find("event: live\ndata: ");
        if (at == std::string::npos) return true;
        const auto end = buf.find("\n\n", at);
        if (end == std::string::npos) return true;
        live = json::parse(buf.substr(at + 18, end - at - 18));
        return false;
    });
    return live;
}

TEST(WebuiDevices, CircularTestOnTheBallBarProtocolStoppedThenResumedFromThePage) {
    ballbar::test::ScratchDir dir("webui-dev");
    const std::string program = dir.file("circle.nc");
    Child emu({BALLBAR_EXE, "emulate", "--pty", "--fast", "--config", emulator_config(dir, program)});
    ASSERT_EQ(emu.first_line.rfind("/dev/pts/", 0), 0u) << emu.first_line;
    const std::string device = "serial:" + emu.first_line;
    Served s(options(dir));
    auto c = s.client();
    json live;
    std::thread watcher([&] { live = first_live_reading(s.port); });
    const json start = {{"procedure", "circular"}, {"device", device},  {"plane", "XY"},  {"radius_mm", 100},
                        {"feed_mm_min", 2000},     {"feed_in_mm", 0.8}, {"arc_deg", 180}, {"dialect", "linuxcnc"}};
    auto r = post(c, "/api/procedure", start);
    ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "no answer");
    int programs = 0;
    // Up to the end of the first run: then the operator presses Stop.
    json state = operate(c, program, programs, [](const json& st) {
        return st["progress"].is_object() && st["progress"].value("done", 0) >= 1;
    });
    watcher.join();
    EXPECT_EQ(programs, 1);
    ASSERT_TRUE(state["running"].get<bool>()) << state.dump(1);
    std::ifstream loaded(program);
    const std::string text((std::istreambuf_iterator<char>(loaded)), {});
    EXPECT_NE(text.find("G2"), std::string::npos) << text;  // the circle's arcs, in the controller's words
    EXPECT_NE(text.find("M2"), std::string::npos) << text;
    // The live reading: the bar's length near the test's radius and the range the bar says it has.
    ASSERT_TRUE(live.is_object());
    EXPECT_NEAR(live["bar_mm"].get<double>(), 100.0, 1.0) << live.dump();
    EXPECT_GT(live["range_mm"].get<double>(), 0.5) << live.dump();

    ASSERT_EQ(post(c, "/api/procedure/stop", json::object())->status, 200);
    while (next_question(c, state)) std::this_thread::sleep_for(20ms);  // a question open at the stop ends too
    EXPECT_EQ(state["state"], "interrupted") << state.dump(1);
    const auto id = state["session"].get<std::int64_t>();
    const json listed = get_json(c, "/api/sessions/" + std::to_string(id));
    EXPECT_TRUE(listed.dump().find("\"resumable\":true") != std::string::npos) << listed.dump(1);

    // The Resume button: the same device, the session's id.
    r = post(c, "/api/procedure", {{"procedure", "circular"}, {"device", device}, {"resume", std::to_string(id)}});
    ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "no answer");
    state = operate(c, program, programs, [](const json&) { return false; });
    EXPECT_EQ(state["state"], "completed") << state.dump(1);
    EXPECT_EQ(state["session"], id);
    EXPECT_EQ(programs, 2);  // the resume runs the program again for the runs it lacks
    ASSERT_EQ(state["result"]["runs"].size(), 2u) << state.dump(1);
    // The emulator's truth, from the stored session's report.
    const json report = get_json(c, "/api/sessions/" + std::to_string(id) + "/report.json");
    double backlash_x = NAN;
    for (const auto& d : report["circular"]["diagnostics"])
        if (d.value("key", "") == "backlash_x_um") backlash_x = d["value"].get<double>();
    EXPECT_NEAR(backlash_x, 4.0, 0.8) << report["circular"]["diagnostics"].dump(1);
}

std::string read_text(const std::string& path) {
    std::ifstream in(path);
    return std::string((std::istreambuf_iterator<char>(in)), {});
}

TEST(WebuiDevices, SsmOnAnInstrumentWithTheMachineAndPlanFilesThePageUploads) {
    ballbar::test::ScratchDir dir("webui-dev");
    const std::string data = std::string(BALLBAR_TEST_DATA_DIR) + "/machines/";
    const std::string program = dir.file("ssm.nc");
    // The emulated TTTRR (its link errors) runs the program the operator loads; simulated time.
    std::string cfg = read_text(data + "tttrr-emulator.json");
    cfg.replace(cfg.find("PROGRAM"), 7, program);
    cfg.replace(cfg.find('{'), 1, "{\"time\": \"simulated\",");
    std::ofstream(dir.file("emulator.json")) << cfg;
    Served s(options(dir));
    auto c = s.client();
    auto r = post(c, "/api/procedure",
                  {{"procedure", "ssm"},
                   {"device", "emulator:" + dir.file("emulator.json")},
                   {"machine_file", read_text(data + "tttrr.json")},
                   {"plan_file", read_text(data + "tttrr-quick.plan.json")}});
    ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "no answer");
    int programs = 0;
    const json end = operate(c, program, programs, [](const json&) { return false; });
    EXPECT_EQ(end["state"], "completed") << end.dump(1);
    EXPECT_GE(programs, 1);
    EXPECT_NE(read_text(program).find("M0"), std::string::npos) << "the measuring program stops for the bar";
    ASSERT_EQ(end["points"].size(), 6u) << end.dump(1);  // one test: six points
    for (const auto& p : end["points"]) EXPECT_EQ(p["verdict"], "ok") << p.dump();
    const json report = get_json(c, "/api/sessions/" + std::to_string(end["session"].get<std::int64_t>()) +
                                        "/report.json?location_tolerance_um=500&angle_tolerance_arcsec=500");
    ASSERT_FALSE(report["locations"].empty()) << report.dump(1).substr(0, 2000);
    for (const auto& l : report["locations"]) EXPECT_TRUE(l["pass"].is_boolean()) << l.dump();  // a verdict each
}

TEST(WebuiDevices, ADigitalGaugeTooSlowForTheFeedIsRefusedWithTheCliMessage) {
    ballbar::test::ScratchDir dir("webui-dev");
    Child gauge({BALLBAR_EXE, "emulate", "--instrument", "sylvac", "--pty", "--rate", "20"});
    ASSERT_EQ(gauge.first_line.rfind("/dev/pts/", 0), 0u) << gauge.first_line;
    Served s(options(dir));
    auto c = s.client();
    auto r = post(c, "/api/procedure",
                  {{"procedure", "circular"},
                   {"device", "sylvac:" + gauge.first_line},
                   {"feed_mm_min", 1000},
                   {"feed_in_mm", 0.8},
                   {"arc_deg", 180}});
    ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "no answer");
    const json end = drive_to_end(c);
    EXPECT_EQ(end["state"], "failed") << end.dump(1);
    EXPECT_TRUE(
        std::regex_search(end["message"].get<std::string>(), std::regex("highest usable feed is [0-9]+ mm/min")))
        << end["message"];
    EXPECT_TRUE(end["session"].is_null()) << "a refused test leaves no session";
}

TEST(WebuiDevices, ADemoWithAPulledCableShowsTheInstrumentLostThenBackAndEndsComplete) {
    ballbar::test::ScratchDir dir("webui-dev");
    Served s(options(dir));
    auto c = s.client();
    // Faults are the emulator's: refused for a real instrument, and checked before anything starts.
    auto r = post(c, "/api/procedure",
                  {{"procedure", "circular"}, {"device", "serial:/dev/null"}, {"faults", {{"disconnect_at_s", 3}}}});
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400);
    EXPECT_NE(r->body.find("only a demo"), std::string::npos) << r->body;
    r = post(c, "/api/procedure", {{"procedure", "ssm"}, {"demo", true}, {"faults", {{"disconnect_at_s", "soon"}}}});
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400);
    EXPECT_NE(r->body.find("faults"), std::string::npos) << r->body;

    r = post(c, "/api/procedure",
             {{"procedure", "ssm"}, {"demo", true}, {"faults", {{"disconnect_at_s", 30}, {"disconnect_s", 8}}}});
    ASSERT_TRUE(r && r->status == 200) << (r ? r->body : "no answer");
    json state;
    bool saw_lost = false;
    while (const auto q = next_question(c, state, 180s)) {
        saw_lost = saw_lost || state["lost"].is_object();
        answer(c, q);
    }
    EXPECT_EQ(state["state"], "completed") << state.dump(1);
    std::string log;
    for (const auto& l : state["log"]) log += l["text"].get<std::string>() + "\n";
    const auto lost = log.find("Instrument lost: check its cable");
    const auto back = log.find("Instrument back.");
    ASSERT_NE(lost, std::string::npos) << log;
    ASSERT_NE(back, std::string::npos) << log;
    EXPECT_LT(lost, back);
    EXPECT_TRUE(state["lost"].is_null()) << "the banner goes once the instrument is back";
    (void)saw_lost;  // shown for a moment only, between two polls: the log is what a test can rely on
}

TEST(WebuiDevices, ServeDemoWaitsForTheFirstScreenAndStopsCleanlyOnSigterm) {
    ballbar::test::ScratchDir dir("webui-dev");
    Child serve({BALLBAR_EXE, "--db", dir.file("sessions.db"), "serve", "--port", "0", "--demo"});
    std::smatch m;
    ASSERT_TRUE(std::regex_search(serve.first_line, m, std::regex("open http://127\\.0\\.0\\.1:([0-9]+)/$")))
        << serve.first_line;
    httplib::Client c("127.0.0.1", std::stoi(m[1].str()));
    c.set_read_timeout(30, 0);
    c.set_default_headers({{"X-Ballbar-Client", "first-screen"}});
    json state;
    ASSERT_GT(next_question(c, state), 0u);  // the demo waits at its first question
    EXPECT_EQ(state["procedure"], "circular");
    EXPECT_TRUE(state["demo"].get<bool>());
    EXPECT_TRUE(state["you_steer"].get<bool>()) << "the first screen that opens steers it";
    EXPECT_EQ(drive_to_end(c)["state"], "completed");
    const int st = serve.stop(SIGTERM);
    ASSERT_TRUE(WIFEXITED(st)) << st;
    EXPECT_EQ(WEXITSTATUS(st), 0);
    EXPECT_FALSE(c.Get("/api/sessions")) << "the server is gone";
    ballbar::storage::StoreOptions so;
    so.read_only = true;
    ballbar::storage::Store store(dir.file("sessions.db"), so);
    const auto sessions = store.sessions();
    ASSERT_EQ(sessions.size(), 1u);
    EXPECT_EQ(sessions[0].state, ballbar::storage::SessionState::completed);
}

}  // namespace
