// SPDX-License-Identifier: MIT
// `ballbar trend MACHINE` (docs/fleet.md): one machine measured from two stations over months; each
// station's trend holds its own sessions, the server's (--from) every station's, with the same figures;
// a drift written into the stored results is flagged; --since, --json, the PDF.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "../app/json_vocabulary.hpp"
#include "../scratch_dir.hpp"
#include "pg_fixture.hpp"

namespace {

using ballbar::test::ballbar_cli;
using ballbar::test::json_in;
using ballbar::test::PgServer;
using ballbar::test::ScratchDir;
using ballbar::test::sh;
using ballbar::test::shq;
using nlohmann::json;

/// A station that measured M-0042 three times, its sessions moved `months` apart starting `first`
/// (sqlite3, as if measured then), and its ΔV grown by `growth` (a fraction) a session.
void station(const std::string& db, int seed, const std::string& first, double growth) {
    const std::string machines = std::string(BALLBAR_TEST_DATA_DIR) + "/machines/";
    ASSERT_EQ(ballbar_cli(db, "machines add M-0042 --machine " + shq(machines + "tttrr.json") +
                                  " --location-tolerance 80 --angle-tolerance 60")
                  .code,
              0);
    for (int i = 0; i < 3; ++i)
        ASSERT_EQ(ballbar_cli(db, "demo --asset M-0042 --seed " + std::to_string(seed + i)).code, 0);
    ASSERT_EQ(
        ballbar::test::sqlite(
            db, "UPDATE sessions SET started_at = strftime('%Y-%m-%dT%H:%M:%fZ', '" + first +
                    "', '+' || ((id - 1) * 61) || ' days'); "
                    "UPDATE results SET payload_json = json_set(payload_json, '$.dV_mm', json_array("
                    "json_extract(payload_json, '$.dV_mm[0]') * g.f, json_extract(payload_json, "
                    "'$.dV_mm[1]') * g.f, json_extract(payload_json, '$.dV_mm[2]') * g.f)) FROM (SELECT id, 1 + " +
                    std::to_string(growth) +
                    " * (id - 1) AS f FROM sessions) g WHERE kind = 'ssm' AND g.id = results.session_id")
            .code,
        0);
}

/// Figure key → (session started_at → value).
std::map<std::string, std::map<std::string, double>> values_of(const json& trend) {
    std::map<std::string, std::map<std::string, double>> out;
    for (const auto& f : trend.at("figures"))
        for (const auto& p : f.at("points")) out[f.at("key")][p.at("started_at")] = p.at("value");
    return out;
}

TEST(PgTrend, TheServersTrendHoldsEveryStationsSessionsWithTheSameFigures) {
    PgServer pg;
    BALLBAR_NEED_SERVER(pg);
    ScratchDir d("trend");
    const std::string a = d.file("a.db"), b = d.file("b.db");
    station(a, 1, "2026-01-10T08:00:00.000Z", 0);
    station(b, 4, "2026-02-10T08:00:00.000Z", 0.05);  // the other station sees the machine drift
    for (const char* id : {"1", "2", "3"})            // a's sessions identified: their parameters join the trend
        ASSERT_EQ(ballbar_cli(a, std::string("identify ") + id).code, 0);
    ASSERT_EQ(ballbar_cli(a, "sync " + shq(pg.super())).code, 0);
    ASSERT_EQ(ballbar_cli(b, "sync " + shq(pg.super())).code, 0);

    const json la = json_in(ballbar_cli(a, "trend M-0042 --json")), lb = json_in(ballbar_cli(b, "trend M-0042 --json"));
    const auto server_run = ballbar_cli(a, "trend M-0042 --json --from " + shq(pg.super()));
    ASSERT_EQ(server_run.code, 0) << server_run.out;
    const json server = json_in(server_run);
    EXPECT_EQ(la.at("sessions"), 3);
    EXPECT_EQ(lb.at("sessions"), 3);
    EXPECT_EQ(server.at("sessions"), 6);
    EXPECT_EQ(ballbar::test::vocabulary_violations(server), std::vector<std::string>{}) << server.dump(2);
    // The server's values are each station's, session by session.
    auto all = values_of(server);
    for (const json* local : {&la, &lb})
        for (const auto& [key, points] : values_of(*local))
            for (const auto& [at, value] :
                 points)  // the server's results come in another order: sums may differ in the last bit
                EXPECT_NEAR(all[key][at], value, 1e-9 * std::abs(value)) << key << " " << at;
    // The figures the trend plots, with their tolerances.
    std::map<std::string, json> by_key;
    for (const auto& f : server.at("figures")) by_key[f.at("key")] = f;
    for (const char* k : {"dV_max_um", "d_alpha_arcsec", "d_gamma_arcsec"}) EXPECT_TRUE(by_key.count(k)) << k;
    EXPECT_EQ(by_key["dV_max_um"].at("tolerance"), 80.0);
    EXPECT_EQ(by_key["d_alpha_arcsec"].at("tolerance"), 60.0);
    EXPECT_GT(by_key["dV_max_um"].at("points").at(0).at("value_std").get<double>(), 0);
    int identified = 0;
    for (const auto& [key, f] : by_key)
        if (f.at("label").get<std::string>().ends_with("(identified)")) {
            ++identified;
            EXPECT_EQ(f.at("points").size(), 3u) << key << ": a's three sessions";
            EXPECT_GT(f.at("points").at(0).at("value_std").get<double>(), 0) << key;
        }
    EXPECT_GE(identified, 2) << server.dump(1);
    // Station a's |ΔV| is steady; b's grows 5 % every two months toward its 80 µm: flagged.
    EXPECT_TRUE(la.at("figures").at(0).at("flag").is_null()) << la.at("figures").at(0).dump();
    EXPECT_EQ(lb.at("figures").at(0).at("flag"), "drifting toward tolerance") << lb.at("figures").at(0).dump();
    EXPECT_GT(by_key["dV_max_um"].at("slope_per_year").get<double>(), 0);

    // --since keeps the later sessions only.
    EXPECT_EQ(
        json_in(ballbar_cli(a, "trend M-0042 --json --since 2026-03-01 --from " + shq(pg.super()))).at("sessions"), 4);

    // The PDF: a page a few figures, the machine, the flag.
    const auto pdf = ballbar_cli(a, "trend M-0042 --from " + shq(pg.super()) + " --out " + shq(d.file("m42.pdf")));
    ASSERT_EQ(pdf.code, 0) << pdf.out;
    const std::string text = sh("pdftotext -layout " + shq(d.file("m42.pdf")) + " -").out;
    EXPECT_NE(text.find("Machine M-0042: trend"), std::string::npos) << text;
    EXPECT_NE(text.find("6 completed sessions"), std::string::npos) << text;
    EXPECT_NE(text.find("SSM |ΔV| largest"), std::string::npos) << text;
    const auto pdf_b = ballbar_cli(b, "trend M-0042 --out " + shq(d.file("b.pdf")));
    ASSERT_EQ(pdf_b.code, 0) << pdf_b.out;
    EXPECT_NE(sh("pdftotext -layout " + shq(d.file("b.pdf")) + " -").out.find("drifting toward tolerance"),
              std::string::npos);

    // Nothing to plot: said, and the PDF refused (exit 2, no file).
    const auto none = ballbar_cli(a, "trend M-9999 --out " + shq(d.file("none.pdf")));
    EXPECT_EQ(none.code, 2) << none.out;
    EXPECT_FALSE(std::filesystem::exists(d.file("none.pdf")));
    EXPECT_EQ(ballbar_cli(a, "trend M-0042 --since 2026/03/01").code, 2);
}

}  // namespace
