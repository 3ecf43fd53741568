// SPDX-License-Identifier: MIT
// Identification as a use case, in process: the inputs (readings files and sessions), the fit, the model
// stored as the next version of its name with an `identification` result on each session, and the
// refusals in their categories. The readings are computed here from the readings format's own
// definition (a TTTRR machine whose C axis line is off by (dx, dy)), sharing no code with the fit.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "../scratch_dir.hpp"
#include "ballbar/storage/readings.hpp"
#include "ballbar/storage/readings_file.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/identify.hpp"

namespace ballbar::workflow {
namespace {

struct V {
    double x, y, z;
};
V rx(double a, V v) {
    return {v.x, std::cos(a) * v.y - std::sin(a) * v.z, std::sin(a) * v.y + std::cos(a) * v.z};
}
V rz(double a, V v) {
    return {std::cos(a) * v.x - std::sin(a) * v.y, std::sin(a) * v.x + std::cos(a) * v.y, v.z};
}
V add(V a, V b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
V sub(V a, V b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
double norm(V a) {
    return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
}

/// A readings file of cube-corner SSM locations on a TTTRR whose C axis is off by (x0c, y0c).
std::string readings_file(double x0c_mm, double y0c_mm, const std::string& name = "wf-test") {
    std::ostringstream f;
    f.precision(17);
    f << "# ballbar-readings/1\n"
      << "# machine: {\"type\":\"TTTRR\",\"name\":\"" << name
      << "\",\"a_pivot_mm\":[0,0,0],\"c_offset_mm\":[0,0,-100],\"tool_ball_mm\":[0,0,0]}\n"
      << "location,point,X_mm,Y_mm,Z_mm,A_deg,C_deg,socket_x_mm,socket_y_mm,socket_z_mm,measured_mm\n";
    const V socket{100, 0, 20}, c_off{0, 0, -100}, d{x0c_mm, y0c_mm, 0};
    const double pi = 3.141592653589793, cone = 0.9553166181245093;
    int loc = 0;
    for (double a_deg : {-60.0, -30.0, 0.0, 30.0, 60.0})
        for (double c_deg : {0.0, 60.0, 120.0, 180.0, 240.0, 300.0}) {
            const double a = a_deg * pi / 180, c = c_deg * pi / 180;
            const V s_nom = rx(a, add(c_off, rz(c, socket)));
            const V s_act = rx(a, add(add(c_off, d), rz(c, sub(socket, d))));
            for (int k = 0; k < 3; ++k) {
                const double az = 2 * pi * k / 3;
                const V b = add(s_nom, V{100 * std::sin(cone) * std::cos(az), 100 * std::sin(cone) * std::sin(az),
                                         100 * std::cos(cone)});
                f << loc << ',' << k << ',' << b.x << ',' << b.y << ',' << b.z << ',' << a_deg << ',' << c_deg << ','
                  << socket.x << ',' << socket.y << ',' << socket.z << ',' << norm(sub(b, s_act)) << '\n';
            }
            ++loc;
        }
    return f.str();
}

const std::vector<analysis::Param> kParams{analysis::Param::X0C, analysis::Param::Y0C, analysis::Param::C_zero};

TEST(IdentifyUseCase, AReadingsFileGivesTheCAxisLocationAndNothingIsStoredWithoutAskingForIt) {
    ballbar::test::ScratchDir d{"identify"};
    const std::vector<std::string> in{d.write("r.csv", readings_file(0.03, -0.02))};
    const ReadingInputs inputs = read_inputs(in, []() -> storage::Store& { throw std::logic_error("no session"); });
    ASSERT_EQ(inputs.sets.size(), 1u);
    EXPECT_TRUE(inputs.sessions.empty());
    IdentifyOptions o;
    o.free_params = kParams;
    o.store_model = false;
    const IdentifyResult r =
        identify(inputs, o, []() -> storage::Store& { throw std::logic_error("nothing to store"); });
    ASSERT_TRUE(r.fit.converged);
    EXPECT_FALSE(r.stored.has_value());
    const analysis::ErrorParams v = r.model.values();
    EXPECT_NEAR(v[analysis::Param::X0C], 0.03, 1e-7);
    EXPECT_NEAR(v[analysis::Param::Y0C], -0.02, 1e-7);
    ASSERT_EQ(r.model.unobservable.size(), 1u);  // a turn of the socket is a socket offset
    EXPECT_EQ(r.model.unobservable[0], analysis::Param::C_zero);
    EXPECT_LT(r.fit.residual_rms_mm, 1e-6);
    // The model as printed and stored reads back through its codec.
    EXPECT_NO_THROW((void)storage::model_from_json(storage::model_to_json(r.model)));
}

TEST(IdentifyUseCase, SessionsGetTheModelsNextVersionAndEachAResult) {
    ballbar::test::ScratchDir d{"identify"};
    storage::Store store((d.path / "db").string());
    const std::int64_t a = storage::import_readings(store, storage::parse_readings(readings_file(0.03, -0.02, "m7")));
    const std::int64_t b = storage::import_readings(store, storage::parse_readings(readings_file(0.03, -0.02, "m7")));
    const StoreOpener opener = [&store]() -> storage::Store& { return store; };
    IdentifyOptions o;
    o.free_params = kParams;
    const std::vector<std::string> keys{std::to_string(a), std::to_string(b)};
    const IdentifyResult first = identify(read_inputs(keys, opener), o, opener);
    ASSERT_TRUE(first.stored.has_value());
    EXPECT_EQ(first.stored->name, "m7") << "the machine's name by default";
    EXPECT_EQ(first.stored->version, 1);
    const IdentifyResult second = identify(read_inputs(keys, opener), o, opener);
    EXPECT_EQ(second.stored->version, 2);
    for (std::int64_t s : {a, b}) {
        int results = 0;
        for (const auto& res : store.results(s))
            if (res.kind == "identification") {
                ++results;
                EXPECT_EQ(res.payload_json, results == 1 ? first.payload_json : second.payload_json);
            }
        EXPECT_EQ(results, 2) << "session " << s;
    }
    const storage::ErrorModel stored = storage::model_from_json(store.model(second.stored->id).params_json);
    EXPECT_NEAR(stored.values()[analysis::Param::X0C], 0.03, 1e-7);
}

TEST(IdentifyUseCase, InputsThatCannotBeUsedAreRefusedInTheirCategory) {
    ballbar::test::ScratchDir d{"identify"};
    storage::Store store((d.path / "db").string());
    const StoreOpener opener = [&store]() -> storage::Store& { return store; };
    auto category = [&](const std::vector<std::string>& in) {
        try {
            IdentifyOptions o;
            o.free_params = kParams;
            (void)identify(read_inputs(in, opener), o, opener);
        } catch (const Error& e) {
            return e.category();
        }
        return ErrorCategory::internal;  // not refused
    };
    EXPECT_EQ(category({"no/such/file.csv"}), ErrorCategory::bad_input);
    EXPECT_EQ(category({"99"}), ErrorCategory::bad_input) << "a key that matches no session";
    EXPECT_EQ(category({d.write("bad.csv", "# ballbar-readings/1\nnot a header\n")}), ErrorCategory::bad_input);
    // Two machines cannot be merged; three readings cannot give three parameters and six socket terms.
    std::string other = readings_file(0, 0);
    other.replace(other.find("c_offset_mm\":[0,0,-100]"), 23, "c_offset_mm\":[0,0,-90]");
    EXPECT_EQ(category({d.write("a.csv", readings_file(0, 0)), d.write("b.csv", other)}), ErrorCategory::bad_input);
    const std::string few = readings_file(0, 0).substr(0, readings_file(0, 0).find("\n1,0,"));
    EXPECT_EQ(category({d.write("few.csv", few + "\n")}), ErrorCategory::failed);
}

}  // namespace
}  // namespace ballbar::workflow
