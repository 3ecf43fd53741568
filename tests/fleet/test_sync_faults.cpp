// SPDX-License-Identifier: MIT
// `ballbar sync` when things go wrong (docs/fleet.md): a server that cannot be reached, a wrong password,
// a password on the command line, a server schema of a newer ballbar, the network cut in the middle of a
// COPY, and a campaign of kills — the client killed, its backend terminated, the server crashed — while
// the station keeps measuring. Each time: a clear message, a non-zero exit, the station's database as it
// was; and after a final sync the server holds exactly what the station has.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <thread>

#include "../scratch_dir.hpp"
#include "pg_fixture.hpp"

namespace {

using ballbar::test::ballbar_cli;
using ballbar::test::json_in;
using ballbar::test::PgServer;
using ballbar::test::ScratchDir;
using ballbar::test::sh;
using ballbar::test::shq;

/// The station's whole content, as sqlite3 dumps it.
std::string dump(const std::string& db) {
    return sh("sqlite3 " + shq(db) + " .dump").out;
}

void make_station(const std::string& db, int seed) {
    const auto demo = ballbar_cli(db, "demo --test circular --plane XY --seed " + std::to_string(seed));
    ASSERT_EQ(demo.code, 0) << demo.out;
}

TEST(PgSyncFaults, AServerThatCannotBeUsedIsNamedAndTheStationIsUntouched) {
    PgServer pg;
    BALLBAR_NEED_SERVER(pg);
    ScratchDir d("fleet");
    const std::string db = d.file("station.db");
    make_station(db, 5);
    ASSERT_EQ(pg.psql("CREATE ROLE station LOGIN PASSWORD 'right'").code, 0);
    const std::string before = dump(db);

    const auto unreachable = ballbar_cli(db, "sync 'host=127.0.0.1 port=1 dbname=ballbar connect_timeout=5'");
    EXPECT_EQ(unreachable.code, 1) << unreachable.out;
    EXPECT_NE(unreachable.out.find("cannot connect to the PostgreSQL server"), std::string::npos) << unreachable.out;
    EXPECT_NE(unreachable.out.find("Connection refused"), std::string::npos) << unreachable.out;

    const auto wrong = ballbar_cli(db, "sync " + shq(pg.tcp("station")), "PGPASSWORD=wrong");
    EXPECT_EQ(wrong.code, 1) << wrong.out;
    EXPECT_NE(wrong.out.find("password authentication failed for user \"station\""), std::string::npos) << wrong.out;

    const auto on_line = ballbar_cli(db, "sync " + shq(pg.tcp("station") + " password=right"));
    EXPECT_EQ(on_line.code, 2) << on_line.out;
    EXPECT_NE(on_line.out.find("holds a password: give it in PGPASSWORD or ~/.pgpass"), std::string::npos)
        << on_line.out;
    const auto uri =
        ballbar_cli(db, "sync 'postgresql://station:right@127.0.0.1:" + std::to_string(pg.port) + "/postgres'");
    EXPECT_EQ(uri.code, 2) << uri.out;

    const auto garbled = ballbar_cli(db, "sync 'host=127.0.0.1 port'");
    EXPECT_EQ(garbled.code, 2) << garbled.out;
    EXPECT_NE(garbled.out.find("the connection string cannot be used"), std::string::npos) << garbled.out;

    // A server a newer ballbar migrated: refused before anything is sent.
    ASSERT_EQ(ballbar_cli(db, "sync " + shq(pg.super())).code, 0);
    ASSERT_EQ(pg.psql("UPDATE ballbar.schema_info SET version = 99").code, 0);
    make_station(db, 6);
    const std::string grown = dump(db);
    const auto newer = ballbar_cli(db, "sync " + shq(pg.super()));
    EXPECT_EQ(newer.code, 1) << newer.out;
    EXPECT_NE(newer.out.find("server schema version 99, newer than this ballbar's (1)"), std::string::npos)
        << newer.out;
    EXPECT_EQ(pg.psql("SELECT count(*) FROM ballbar.sessions").out, "1\n");

    EXPECT_EQ(dump(db), grown) << "a refused sync leaves the station's database as it was";
    EXPECT_NE(before, grown);
}

/// A TCP relay between the client and the server that cuts both sides once `cut_after` bytes went from
/// the client to the server: the network failing in the middle of a transfer.
class CuttingRelay {
  public:
    CuttingRelay(int server_port, std::size_t cut_after) : server_port_(server_port), cut_after_(cut_after) {
        listener_ = ::socket(AF_INET, SOCK_STREAM, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        if (::bind(listener_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(listener_, 4) != 0)
            throw std::runtime_error("relay: cannot listen");
        socklen_t n = sizeof a;
        ::getsockname(listener_, reinterpret_cast<sockaddr*>(&a), &n);
        port = ntohs(a.sin_port);
        thread_ = std::thread([this] { relay(); });
    }
    ~CuttingRelay() {
        stop_ = true;
        ::shutdown(listener_, SHUT_RDWR);
        thread_.join();
        ::close(listener_);
    }
    int port = 0;
    std::atomic<std::size_t> sent{0};
    std::atomic<bool> cut{false};

  private:
    void relay() {
        pollfd l{listener_, POLLIN, 0};
        while (!stop_) {
            if (::poll(&l, 1, 100) <= 0) continue;
            const int client = ::accept(listener_, nullptr, nullptr);
            if (client < 0) continue;
            const int server = ::socket(AF_INET, SOCK_STREAM, 0);
            sockaddr_in a{};
            a.sin_family = AF_INET;
            a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
            a.sin_port = htons(static_cast<std::uint16_t>(server_port_));
            if (::connect(server, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0) pump(client, server);
            ::close(client);
            ::close(server);
        }
    }
    void pump(int client, int server) {
        pollfd f[2] = {{client, POLLIN, 0}, {server, POLLIN, 0}};
        char buf[16384];
        while (!stop_) {
            if (::poll(f, 2, 100) <= 0) continue;
            for (int i = 0; i < 2; ++i) {
                if (!(f[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
                const ssize_t n = ::read(f[i].fd, buf, sizeof buf);
                if (n <= 0) return;
                if (i == 0 && (sent += static_cast<std::size_t>(n)) > cut_after_) {
                    cut = true;  // the link dies: neither side hears from the other again
                    return;
                }
                if (::write(f[1 - i].fd, buf, static_cast<std::size_t>(n)) != n) return;
            }
        }
    }
    int listener_ = -1;
    int server_port_;
    std::size_t cut_after_;
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

TEST(PgSyncFaults, TheNetworkCutMidCopyLosesOnlyTheChunkInFlight) {
    PgServer pg;
    BALLBAR_NEED_SERVER(pg);
    ScratchDir d("fleet");
    const std::string db = d.file("station.db");
    make_station(db, 7);
    make_station(db, 8);
    ASSERT_EQ(pg.psql("CREATE ROLE station LOGIN PASSWORD 'pw'; CREATE SCHEMA ballbar AUTHORIZATION station").code, 0);
    const std::string before = dump(db);
    {
        CuttingRelay relay(pg.port, 1500000);  // past the records, in the samples
        const auto r = ballbar_cli(db, "sync " + shq(pg.tcp("station", relay.port)) + " --samples --chunk 5000",
                                   "PGPASSWORD=pw timeout 60");
        EXPECT_TRUE(relay.cut) << "the relay saw only " << relay.sent << " bytes: " << r.out;
        EXPECT_EQ(r.code, 1) << r.out;
        EXPECT_NE(r.out.find("the connection to the PostgreSQL server broke"), std::string::npos) << r.out;
    }
    EXPECT_EQ(dump(db), before);
    const long partial = std::stol(pg.psql("SELECT count(*) FROM ballbar.samples").out);
    EXPECT_GT(partial, 0) << "chunks committed before the cut stay";
    EXPECT_EQ(partial % 5000, 0) << "whole chunks only";
    // The next sync continues from the server's mark.
    const auto resumed = ballbar_cli(db, "sync " + shq(pg.tcp("station")) + " --samples --json", "PGPASSWORD=pw");
    ASSERT_EQ(resumed.code, 0) << resumed.out;
    const auto report = json_in(resumed);
    const long total = std::stol(ballbar::test::sqlite(db, "SELECT count(*) FROM samples").out);
    EXPECT_EQ(report.at("rows").at("samples").get<long>(), total - partial);
    const std::string station = ballbar::test::station_uuid(db);
    EXPECT_EQ(ballbar::test::server_digest(pg, station, true), ballbar::test::station_digest(db, true));
}

TEST(PgSyncFaults, KilledAtRandomWhileTheStationMeasuresAndTheFinalSyncIsExact) {
    PgServer pg;
    BALLBAR_NEED_SERVER(pg);
    ScratchDir d("fleet");
    const std::string db = d.file("station.db");
    make_station(db, 9);
    const std::string conn = pg.super() + " application_name=ballbar-sync-under-test";
    // The station keeps measuring all along.
    std::atomic<bool> done{false};
    std::atomic<int> measured{0};
    std::thread station([&] {
        for (int seed = 10; !done; ++seed)
            if (ballbar_cli(db, "demo --test circular --plane XY --seed " + std::to_string(seed)).code == 0) ++measured;
    });
    std::mt19937 rng(20261206);
    const char* faults[] = {"client killed", "backend terminated", "server crashed"};
    int interrupted = 0;
    // Nine faults at least, and on until the station has stored a session meanwhile (slower under the sanitizers).
    for (int round = 0; round < 60 && (round < 9 || measured == 0); ++round) {
        const std::string fault = faults[round % 3];
        const pid_t child = ::fork();
        if (child == 0) {
            const std::string cmd = shq(BALLBAR_EXE) + " --db " + shq(db) + " sync " + shq(conn) +
                                    " --samples --chunk 2000 >/dev/null 2>&1";
            ::execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
            ::_exit(127);
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(std::uniform_int_distribution<int>(20, 400)(rng)));
        if (fault == std::string("client killed")) {
            ::kill(child, SIGKILL);
        } else if (fault == std::string("backend terminated")) {
            pg.psql(
                "SELECT pg_terminate_backend(pid) FROM pg_stat_activity WHERE application_name = "
                "'ballbar-sync-under-test'");
        } else {
            pg.crash();
        }
        int status = 0;
        ::waitpid(child, &status, 0);
        if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0)) ++interrupted;
    }
    done = true;
    station.join();
    EXPECT_GT(measured.load(), 0) << "the station measured during the campaign";
    EXPECT_GT(interrupted, 2) << "the faults hit syncs in flight";
    const auto last = ballbar_cli(db, "sync " + shq(pg.super()) + " --samples");
    ASSERT_EQ(last.code, 0) << last.out;
    const std::string station_id = ballbar::test::station_uuid(db);
    EXPECT_EQ(ballbar::test::server_digest(pg, station_id, true), ballbar::test::station_digest(db, true));
    EXPECT_EQ(ballbar::test::server_results(pg, station_id), ballbar::test::station_results(db));
    const auto again = ballbar_cli(db, "sync " + shq(pg.super()) + " --samples --json");
    ASSERT_EQ(again.code, 0) << again.out;
    EXPECT_EQ(json_in(again).at("rows_written"), 0);
}

}  // namespace
