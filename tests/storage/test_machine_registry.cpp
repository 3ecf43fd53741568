// SPDX-License-Identifier: MIT
// The machine registry and the fleet's identities (schema v7): asset ids, the station's id, uuids that
// two databases never share.
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "ballbar/storage/machine_json.hpp"
#include "ballbar/storage/store.hpp"
#include "test_util.hpp"

namespace ballbar::storage {
namespace {

using test::TempDir;

StoreOptions same_clock() {
    StoreOptions o;
    o.clock = [] { return std::chrono::system_clock::time_point(std::chrono::seconds(1'800'000'000)); };
    return o;
}

NewMachine mill(const std::string& asset) {
    NewMachine n;
    n.asset_id = asset;
    n.name = "DMU 50 #" + asset;
    n.location = "hall 2, cell 4";
    n.geometry = test::tttrr();
    n.machine_file_json = R"({"format":"ballbar-machine/1"})";
    return n;
}

TEST(MachineRegistry, ARegisteredMachineIsFoundByItsAssetIdAndCountsItsSessions) {
    TempDir dir;
    Store store(dir.file("a.db"));
    const MachineEntry m = store.register_machine(mill("M-17"));
    EXPECT_EQ(m.asset_id, "M-17");
    EXPECT_EQ(m.location, "hall 2, cell 4");
    EXPECT_EQ(m.type, analysis::MachineType::TTTRR);
    EXPECT_EQ(m.uuid.size(), 36u);
    EXPECT_FALSE(m.registered_at.empty());
    // Two mills of one model share a geometry and stay two machines.
    store.register_machine(mill("M-18"));
    NewSession s;
    s.machine = test::tttrr();
    s.machine_asset = "M-18";
    s.source = SessionSource::emulator;
    const auto id = store.create_session(s);
    EXPECT_EQ(store.session(id).machine_asset, "M-18");
    EXPECT_EQ(store.machine("M-18").session_count, 1);
    EXPECT_EQ(store.machine("M-17").session_count, 0);
    ASSERT_EQ(store.machines().size(), 2u);
    EXPECT_EQ(store.machines()[0].asset_id, "M-17");
}

TEST(MachineRegistry, ATakenAssetIdAnUnknownOneAndAForeignGeometryAreRefusedNamingThem) {
    TempDir dir;
    Store store(dir.file("a.db"));
    store.register_machine(mill("M-17"));
    try {
        store.register_machine(mill("M-17"));
        FAIL() << "registered twice";
    } catch (const StorageError& e) {
        EXPECT_EQ(e.kind(), StorageError::Kind::invalid);
        EXPECT_NE(std::string(e.what()).find("M-17 is registered already"), std::string::npos) << e.what();
    }
    try {
        store.machine("M-99");
        FAIL() << "found a machine never registered";
    } catch (const StorageError& e) {
        EXPECT_EQ(e.kind(), StorageError::Kind::not_found);
        EXPECT_NE(std::string(e.what()).find("there are M-17"), std::string::npos) << e.what();
    }
    NewSession s;
    s.machine = test::tttrr();
    s.machine.tool_ball_mm.z() += 5;
    s.machine_asset = "M-17";
    EXPECT_THROW(store.create_session(s), StorageError);
    EXPECT_TRUE(store.sessions().empty());
}

TEST(MachineRegistry, AnEditKeepsWhatItDoesNotNameAndTheGeometryOfAMeasuredMachine) {
    TempDir dir;
    Store store(dir.file("a.db"));
    store.register_machine(mill("M-17"));
    MachineEdit e;
    e.location = "hall 3";
    auto g = test::tttrr();
    g.tool_ball_mm.z() += 5;
    e.geometry = g;
    MachineEntry m = store.edit_machine("M-17", e);  // no session yet: the geometry may change
    EXPECT_EQ(m.location, "hall 3");
    EXPECT_EQ(m.name, "DMU 50 #M-17");
    EXPECT_EQ(m.geometry_json, machine_to_json(g));
    EXPECT_FALSE(m.updated_at.empty());
    NewSession s;
    s.machine = g;
    s.machine_asset = "M-17";
    store.create_session(s);
    MachineEdit back;
    back.geometry = test::tttrr();
    EXPECT_THROW(store.edit_machine("M-17", back), StorageError);
    EXPECT_EQ(store.machine("M-17").geometry_json, machine_to_json(g));
}

// Two stations with the same clock (and, in tests, the same emulator seeds) never hand out one id twice.
TEST(MachineRegistry, TwoDatabasesNeverShareAnId) {
    TempDir dir;
    Store a(dir.file("a.db"), same_clock()), b(dir.file("b.db"), same_clock());
    EXPECT_NE(a.station_uuid(), b.station_uuid());
    NewSession s;
    s.machine = test::tttrr();
    s.source = SessionSource::emulator;
    for (int i = 0; i < 20; ++i) {
        const auto ia = a.create_session(s), ib = b.create_session(s);
        EXPECT_NE(a.session(ia).uuid, b.session(ib).uuid);
        EXPECT_NE(
            a.db().query_text("SELECT uuid FROM results WHERE id = " + std::to_string(a.add_result(ia, "x", "{}"))),
            b.db().query_text("SELECT uuid FROM results WHERE id = " + std::to_string(b.add_result(ib, "x", "{}"))));
    }
    EXPECT_NE(a.save_model("m", "{}").id, 0);
    EXPECT_NE(a.db().query_text("SELECT uuid FROM models"), b.save_model("m", "{}").name);
    EXPECT_NE(a.db().query_text("SELECT uuid FROM models"), b.db().query_text("SELECT uuid FROM models"));
    EXPECT_NE(a.db().query_text("SELECT uuid FROM machines"), b.db().query_text("SELECT uuid FROM machines"));
}

}  // namespace
}  // namespace ballbar::storage
