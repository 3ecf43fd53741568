// SPDX-License-Identifier: MIT
// The stored `instrument` result (a digital gauge and what the session measured of it): written and read
// back; a gauge never identified has no identity; an unknown key or a mistyped count is refused naming it.
#include <gtest/gtest.h>

#include <string>

#include "ballbar/storage/instrument_result.hpp"
#include "ballbar/storage/machine_json.hpp"

namespace ballbar::storage {
namespace {

TEST(InstrumentResult, WrittenAndReadBack) {
    GaugeInstrumentRecord r;
    r.kind = "sylvac";
    r.maker = "Sylvac";
    r.model = "S_Dial";
    r.firmware = "1.2";
    r.uri = "sylvac:/dev/ttyUSB0";
    r.resolution_mm = 1e-4;
    r.reading_rate_hz = 19.8;
    r.target_rate_hz = 20;
    r.calibrated_length_mm = 100;
    r.sign = -1;
    r.readings = 1234;
    r.timeouts = 2;
    const GaugeInstrumentRecord back = gauge_instrument_from_json(gauge_instrument_to_json(r));
    EXPECT_EQ(back.maker, "Sylvac");
    EXPECT_FALSE(back.serial.has_value());  // null, not ""
    EXPECT_EQ(back.firmware, "1.2");
    EXPECT_DOUBLE_EQ(back.reading_rate_hz, 19.8);
    EXPECT_EQ(back.sign, -1);
    EXPECT_EQ(back.readings, 1234u);
    EXPECT_EQ(back.timeouts, 2u);

    GaugeInstrumentRecord anonymous;  // the gauge never answered its identity
    anonymous.uri = "modbus:/dev/ttyUSB1";
    EXPECT_TRUE(gauge_instrument_from_json(gauge_instrument_to_json(anonymous)).kind.empty());
}

TEST(InstrumentResult, AnUnknownKeyOrAMistypedCountIsRefusedNamingIt) {
    GaugeInstrumentRecord r;
    r.uri = "digimatic:/dev/ttyUSB0";
    std::string text = gauge_instrument_to_json(r);
    for (const auto& [bad, key] :
         {std::pair<std::string, std::string>{text.substr(0, text.size() - 1) + R"(,"speed":1})", "speed"},
          {std::string(text).replace(text.find("\"readings\":0"), 12, "\"readings\":-1"), "readings"}}) {
        try {
            gauge_instrument_from_json(bad);
            ADD_FAILURE() << bad;
        } catch (const FormatError& e) {
            EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
        }
    }
}

}  // namespace
}  // namespace ballbar::storage
