// SPDX-License-Identifier: MIT
// `ballbar serve`'s JSON API in process, through real HTTP on a loopback port (cpp-httplib's client):
// whole demos driven as a page drives them, what it refuses (token, cross-origin, malformed, unknown,
// a second driver, a second server), 50 viewers at once, and a stop in the middle of a procedure.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "../scratch_dir.hpp"
#include "ballbar/storage/session_export.hpp"
#include "ballbar/storage/store.hpp"
#include "webui_client.hpp"

namespace {

using json = nlohmann::json;
using ballbar::webui::ServeOptions;
using ballbar::webui::Server;
using namespace ballbar::test::webui;
using namespace std::chrono_literals;

TEST(WebuiApi, CircularDemoFromStartToReportAsThePageDrivesIt) {
    ballbar::test::ScratchDir dir("webui");
    Served s(options(dir));
    auto c = s.client();
    auto r = post(c, "/api/procedure", {{"procedure", "circular"}, {"demo", true}});
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << r->body;
    std::vector<std::string> asked;
    const json end = drive_to_end(c, &asked);
    EXPECT_EQ(end["state"], "completed") << end.dump(2);
    EXPECT_EQ(asked, (std::vector<std::string>{"reference", "setup", "run-part-program", "review"}));
    EXPECT_EQ(end["step"]["n"], 6);
    ASSERT_EQ(end["result"]["runs"].size(), 2u);
    EXPECT_TRUE(end["result"]["pass"].get<bool>());  // the diagnosis matches the emulator's truth
    const auto id = end["session"].get<std::int64_t>();

    // The list is what `ballbar sessions --json` prints: the same function of the same database.
    const auto listed = get_json(c, "/api/sessions");
    ballbar::storage::StoreOptions so;
    so.read_only = true;
    ballbar::storage::Store store(dir.file("sessions.db"), so);
    EXPECT_EQ(listed, json::parse(ballbar::storage::sessions_json(store)));
    ASSERT_EQ(listed.size(), 1u);
    EXPECT_EQ(listed[0]["state"], "completed");

    const auto report = get_json(c, "/api/sessions/" + std::to_string(id) + "/report.json?tolerance_um=80");
    ASSERT_TRUE(report["circular"].is_object());
    EXPECT_EQ(report["circular"]["runs"].size(), 2u);
    EXPECT_EQ(report["circular"]["tolerance"]["circularity_um"], 80.0);
    EXPECT_FALSE(report["circular"]["runs"][0]["polar"]["angle_deg"].empty());
    auto pdf = c.Get(("/api/sessions/" + std::to_string(id) + "/report.pdf").c_str());
    ASSERT_TRUE(pdf);
    EXPECT_EQ(pdf->status, 200);
    EXPECT_EQ(pdf->get_header_value("Content-Type"), "application/pdf");
    EXPECT_EQ(pdf->body.rfind("%PDF-", 0), 0u);
    auto trace = c.Get(("/api/sessions/" + std::to_string(id) + "/export?format=trace").c_str());
    ASSERT_TRUE(trace);
    EXPECT_EQ(trace->status, 200);
    EXPECT_NE(trace->body.find("ballbar-trace/1"), std::string::npos);
}

TEST(WebuiApi, SsmDemoShowsEachPointWithItsVerdictAndEndsWithEveryPointAtItsPose) {
    ballbar::test::ScratchDir dir("webui");
    Served s(options(dir));
    auto c = s.client();
    ASSERT_EQ(post(c, "/api/procedure", {{"procedure", "ssm"}, {"demo", true}, {"machine", "TTTRR"}})->status, 200);
    std::vector<std::string> asked;
    const json end = drive_to_end(c, &asked);
    EXPECT_EQ(end["state"], "completed") << end.dump(2);
    EXPECT_EQ(asked.front(), "reference");
    EXPECT_NE(std::find(asked.begin(), asked.end(), "run-program"), asked.end());
    EXPECT_NE(std::find(asked.begin(), asked.end(), "program-stop"), asked.end());
    EXPECT_EQ(asked.back(), "review");
    EXPECT_EQ(end["result"]["wrong_pose"], 0);
    ASSERT_EQ(end["points"].size(), end["result"]["points"].get<std::size_t>());
    for (const auto& p : end["points"]) EXPECT_EQ(p["verdict"], "ok") << p.dump();
    const std::string session = std::to_string(end["session"].get<int>());
    const auto report = get_json(c, "/api/sessions/" + session + "/report.json");
    EXPECT_EQ(report["locations"].size(), 8u);                                   // four tests, two steps each
    for (const auto& l : report["locations"]) EXPECT_TRUE(l["pass"].is_null());  // no tolerance, no verdict

    // Verdicts against the user's tolerances: |ΔV| and |angle| within them, each judged on its own.
    const auto judged =
        get_json(c, "/api/sessions/" + session + "/report.json?location_tolerance_um=30&angle_tolerance_arcsec=50");
    int pass = 0, fail = 0;
    for (const auto& l : judged["locations"]) {
        const auto& v = l["dV_um"];
        const double mag = std::sqrt(v[0].get<double>() * v[0].get<double>() + v[1].get<double>() * v[1].get<double>() +
                                     v[2].get<double>() * v[2].get<double>());
        EXPECT_EQ(l["pass"].get<bool>(), mag <= 30.0) << l.dump();
        (l["pass"].get<bool>() ? pass : fail)++;
    }
    for (const auto& o : judged["orientation"]) {
        EXPECT_EQ(o["pass"].get<bool>(), std::abs(o["exact_arcsec"].get<double>()) <= 50.0) << o.dump();
        (o["pass"].get<bool>() ? pass : fail)++;
    }
    EXPECT_GT(pass, 0);
    EXPECT_GT(fail, 0);  // the demo's errors straddle these tolerances: both verdicts are exercised
    auto bad = c.Get(("/api/sessions/" + session + "/report.json?angle_tolerance_arcsec=-1").c_str());
    ASSERT_TRUE(bad);
    EXPECT_EQ(bad->status, 400);
    EXPECT_NE(bad->body.find("angle_tolerance_arcsec"), std::string::npos);
}

TEST(WebuiApi, TrendOfAMachineIsWhatTheCliPrintsAndFollowsEachSessionsResult) {
    ballbar::test::ScratchDir dir("webui");
    Served s(options(dir));
    auto c = s.client();
    std::vector<double> g;  // each session's G, from its report (the largest of its runs)
    for (int seed : {1, 2}) {
        ASSERT_EQ(post(c, "/api/procedure", {{"procedure", "circular"}, {"demo", true}, {"seed", seed}})->status, 200);
        const json end = drive_to_end(c);
        ASSERT_EQ(end["state"], "completed");
        const auto report = get_json(c, "/api/sessions/" + std::to_string(end["session"].get<int>()) + "/report.json");
        double worst = 0;
        for (const auto& r : report["circular"]["runs"]) worst = std::max(worst, r["circularity_um"].get<double>());
        g.push_back(worst);
    }
    const std::string machine = get_json(c, "/api/sessions")[0]["machine"]["type"].get<std::string>() + " " +
                                get_json(c, "/api/sessions")[0]["machine"]["name"].get<std::string>();
    std::string query;  // percent-encoded
    for (unsigned char ch : machine) {
        char hex[4];
        std::snprintf(hex, sizeof hex, "%%%02X", ch);
        query += std::isalnum(ch) ? std::string(1, static_cast<char>(ch)) : std::string(hex);
    }
    const json trend = get_json(c, "/api/trend?machine=" + query);
    EXPECT_EQ(trend["machine"], machine);
    ASSERT_EQ(trend["points"].size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
        const auto& f = trend["points"][i]["figures"];
        EXPECT_NEAR(f["G_um"].get<double>(), g[i], 1e-9);
        EXPECT_TRUE(f.contains("backlash_x_um") && f.contains("squareness_um_per_m")) << f.dump();
        EXPECT_TRUE(trend["points"][i]["demo"].get<bool>());
    }
    EXPECT_TRUE(get_json(c, "/api/trend?machine=no%20such%20machine")["points"].empty());
    EXPECT_EQ(c.Get("/api/trend")->status, 400);

    // The CLI prints the same JSON: one use case, one vocabulary.
    const std::string cmd =
        std::string(BALLBAR_EXE) + " --db " + dir.file("sessions.db") + " sessions trend '" + machine + "' --json";
    FILE* pipe = ::popen(cmd.c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string printed;
    char buf[4096];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, pipe)) > 0;) printed.append(buf, n);
    EXPECT_EQ(::pclose(pipe), 0);
    EXPECT_EQ(json::parse(printed), trend);
}

TEST(WebuiApi, RefusesWhatItMustWithAClearMessage) {
    ballbar::test::ScratchDir dir("webui");
    Served s(options(dir));
    auto c = s.client();
    auto expect = [](const httplib::Result& r, int status, const std::string& says) {
        ASSERT_TRUE(r);
        EXPECT_EQ(r->status, status) << r->body;
        EXPECT_NE(json::parse(r->body)["error"].get<std::string>().find(says), std::string::npos) << r->body;
    };
    expect(c.Post("/api/procedure", "{not json", "application/json"), 400, "malformed");
    expect(post(c, "/api/procedure", {{"procedure", "drill"}, {"demo", true}}), 400, "\"procedure\"");
    expect(post(c, "/api/procedure", {{"procedure", "ssm"}}), 400, "device");
    expect(c.Post("/api/procedure", R"({"procedure":"ssm","demo":true})", "text/plain"), 403, "Content-Type");
    {
        httplib::Headers h{{"Origin", "http://evil.example"}};
        expect(c.Post("/api/procedure", h, R"({"procedure":"ssm","demo":true})", "application/json"), 403,
               "cross-origin");
    }
    {
        httplib::Headers h{{"Host", "attacker.example:80"}};  // a rebound DNS name
        expect(c.Get("/api/sessions", h), 403, "Host");
    }
    expect(c.Get("/api/sessions/999"), 404, "999");
    expect(c.Get("/api/sessions/999/report.pdf"), 404, "999");
    expect(c.Get("/../../etc/passwd"), 404, "no such page");
    expect(c.Get("/api/procedure/program"), 404, "no program");
    expect(post(c, "/api/procedure/answer", {{"question", 1}, {"option", 0}}), 409, "no procedure");
    expect(post(c, "/api/procedure/stop", json::object()), 409, "no procedure");

    // One steers, the others watch: a second screen with its stream open cannot answer or stop.
    ASSERT_EQ(post(c, "/api/procedure", {{"procedure", "circular"}, {"demo", true}})->status, 200);
    json state;
    const auto q = next_question(c, state);
    ASSERT_GT(q, 0u);
    expect(post(c, "/api/procedure", {{"procedure", "circular"}, {"demo", true}}), 409, "running");
    expect(post(c, "/api/procedure/answer", {{"question", q + 1}, {"option", 0}}), 409, "not being asked");
    expect(post(c, "/api/procedure/answer", {{"question", q}, {"option", 7}}), 400, "option 7");
    auto other = s.client("page-2");
    {
        // The steering page has its event stream open: the second screen may only watch.
        std::atomic<bool> open{false}, done{false};
        httplib::Client sse("127.0.0.1", s.port);
        std::thread stream([&] {
            sse.Get("/api/events?client=page-1", [&](const char*, std::size_t) {
                open = true;
                return !done.load();
            });
        });
        while (!open) std::this_thread::sleep_for(5ms);
        EXPECT_FALSE(get_json(other, "/api/procedure")["you_steer"].get<bool>());
        expect(post(other, "/api/procedure/answer", {{"question", q}, {"option", 0}}), 403, "watch");
        expect(post(other, "/api/procedure/stop", json::object()), 403, "watch");
        done = true;
        sse.stop();
        stream.join();
    }
    // Its browser closed: the second screen takes over (once the server notices, within ~2 s).
    const auto until = std::chrono::steady_clock::now() + 10s;
    while (!get_json(other, "/api/procedure")["you_steer"].get<bool>() && std::chrono::steady_clock::now() < until)
        std::this_thread::sleep_for(50ms);
    EXPECT_TRUE(get_json(other, "/api/procedure")["you_steer"].get<bool>());
    ASSERT_EQ(post(other, "/api/procedure/stop", json::object())->status, 200);
    while (get_json(other, "/api/procedure")["running"].get<bool>()) std::this_thread::sleep_for(20ms);
    EXPECT_EQ(get_json(other, "/api/procedure")["state"], "interrupted");
}

TEST(WebuiApi, TokenIsNeededOnEveryRequestWhenOneIsSet) {
    ballbar::test::ScratchDir dir("webui");
    ServeOptions o = options(dir);
    o.token = "0123456789abcdef0123456789abcdef";
    Served s(o);
    auto c = s.client();
    EXPECT_EQ(c.Get("/")->status, 401);
    EXPECT_EQ(c.Get("/api/sessions")->status, 401);
    EXPECT_EQ(c.Get("/api/sessions?token=0123456789abcdef0123456789abcdee")->status, 401);
    EXPECT_EQ(c.Get("/api/events?token=wrong")->status, 401);
    EXPECT_EQ(c.Get("/?token=0123456789abcdef0123456789abcdef")->status, 200);
    c.set_bearer_token_auth(o.token.c_str());
    EXPECT_EQ(c.Get("/api/sessions")->status, 200);
    c.set_bearer_token_auth("0123456789abcdef0123456789abcdeX");
    EXPECT_EQ(post(c, "/api/procedure", {{"procedure", "ssm"}, {"demo", true}})->status, 401);
}

TEST(WebuiApi, SecondServerOnTheSamePortFailsToBindInsteadOfSharingIt) {
    ballbar::test::ScratchDir dir("webui");
    Served first(options(dir));
    ServeOptions o = options(dir);
    o.port = first.port;
    Server second(o);
    EXPECT_THROW(second.bind(), std::exception);
}

TEST(WebuiApi, FiftyViewersWatchAWholeDemoAndEachSeesItsEnd) {
    ballbar::test::ScratchDir dir("webui");
    Served s(options(dir));
    constexpr int kViewers = 50;
    std::atomic<int> saw_end{0}, saw_live{0}, connected{0};
    std::vector<std::unique_ptr<httplib::Client>> clients;
    std::vector<std::thread> viewers;
    for (int i = 0; i < kViewers; ++i) {
        clients.push_back(std::make_unique<httplib::Client>("127.0.0.1", s.port));
        clients.back()->set_read_timeout(60, 0);
        viewers.emplace_back([&, i] {
            std::string buf;
            bool live = false;
            bool counted = false;
            clients[static_cast<std::size_t>(i)]->Get(
                ("/api/events?client=viewer-" + std::to_string(i)).c_str(), [&](const char* d, std::size_t n) {
                    if (!counted) {
                        counted = true;
                        ++connected;
                    }
                    buf.append(d, n);
                    if (!live && buf.find("event: live") != std::string::npos) {
                        live = true;
                        ++saw_live;
                    }
                    if (buf.find("\"state\":\"completed\"") != std::string::npos) {
                        ++saw_end;
                        return false;
                    }
                    if (buf.size() > 65536) buf.erase(0, buf.size() - 8192);  // keep the tail
                    return true;
                });
        });
    }
    while (connected < kViewers) std::this_thread::sleep_for(10ms);
    auto c = s.client("driver");
    EXPECT_EQ(get_json(c, "/api/procedure")["viewers"], kViewers);
    // A plain request still gets through beside 50 open streams.
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_EQ(c.Get("/api/sessions")->status, 200);
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 2s);  // not starved of a worker (it took 1.5 s with 8)
    ASSERT_EQ(post(c, "/api/procedure", {{"procedure", "circular"}, {"demo", true}})->status, 200);
    EXPECT_EQ(drive_to_end(c)["state"], "completed");
    for (auto& v : viewers) v.join();
    EXPECT_EQ(saw_end, kViewers);
    EXPECT_EQ(saw_live, kViewers);
}

TEST(WebuiApi, StopDuringAProcedureKeepsWhatWasMeasuredAndTheSessionResumable) {
    ballbar::test::ScratchDir dir("webui");
    auto served = std::make_unique<Served>(options(dir));
    auto c = served->client();
    ASSERT_EQ(post(c, "/api/procedure", {{"procedure", "ssm"}, {"demo", true}})->status, 200);
    json state;
    // Answer until the review: every point is stored by then, and the question is open.
    for (;;) {
        const auto q = next_question(c, state);
        ASSERT_GT(q, 0u) << state.dump(2);
        if (state["question"]["what"] == "review") break;
        post(c, "/api/procedure/answer", {{"question", q}, {"option", 0}});
    }
    const auto points = state["points"].size();
    ASSERT_GT(points, 0u);
    const auto id = state["session"].get<std::int64_t>();
    served.reset();  // the server stops (as on SIGTERM) with the question open

    ballbar::storage::StoreOptions so;
    so.read_only = true;
    ballbar::storage::Store store(dir.file("sessions.db"), so);
    const auto info = store.session(id);
    EXPECT_EQ(info.state, ballbar::storage::SessionState::interrupted);
    EXPECT_TRUE(info.resumable());
    EXPECT_EQ(store.points(id).size(), points);
}

}  // namespace
