// SPDX-License-Identifier: MIT
// The udev rules in udev/ must match the USB ID table in the code (ballbar/device/ids.hpp).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "ballbar/device/ids.hpp"

namespace ballbar::device {
namespace {

struct Rule {
    int line = 0;
    std::multimap<std::string, std::pair<std::string, std::string>> keys;  // key -> (operator, value)
    std::string get(const std::string& key) const {
        auto it = keys.find(key);
        return it == keys.end() ? "" : it->second.second;
    }
    bool has(const std::string& key, const std::string& op, const std::string& value) const {
        auto [b, e] = keys.equal_range(key);
        for (auto it = b; it != e; ++it) {
            if (it->second.first == op && it->second.second == value) return true;
        }
        return false;
    }
};

std::vector<Rule> parse_rules(const std::string& path) {
    std::ifstream in(path);
    EXPECT_TRUE(in) << "cannot read " << path;
    std::vector<Rule> rules;
    const std::regex token(R"re(\s*([A-Za-z_]+(\{[^}]*\})?)\s*(==|!=|\+=|-=|:=|=)\s*"([^"]*)"\s*(,|$))re");
    std::string text;
    int n = 0;
    while (std::getline(in, text)) {
        ++n;
        if (text.find_first_not_of(" \t") == std::string::npos || text[text.find_first_not_of(" \t")] == '#') {
            continue;
        }
        Rule r;
        r.line = n;
        auto pos = text.cbegin();
        std::smatch m;
        while (pos != text.cend() &&
               std::regex_search(pos, text.cend(), m, token, std::regex_constants::match_continuous)) {
            r.keys.emplace(m[1].str(), std::make_pair(m[3].str(), m[4].str()));
            pos = m[0].second;
        }
        EXPECT_TRUE(pos == text.cend()) << path << ":" << n << ": cannot parse rule: " << text;
        rules.push_back(r);
    }
    return rules;
}

const char* subsystem_for(UsbLink link) {
    switch (link) {
        case UsbLink::UsbBulk:
            return "usb";
        case UsbLink::Hid:
            return "hidraw";
        case UsbLink::Serial:
            return "tty";
    }
    return "?";
}

std::string id_of(const Rule& r, const char* what) {
    const std::string a = r.get(std::string("ATTR{") + what + "}");
    return a.empty() ? r.get(std::string("ATTRS{") + what + "}") : a;
}

void check_common(const std::string& path, const std::vector<Rule>& rules) {
    ASSERT_FALSE(rules.empty()) << path;
    const std::regex hex4("[0-9a-f]{4}");
    for (const Rule& r : rules) {
        const std::string where = path + ":" + std::to_string(r.line);
        const std::string vid = id_of(r, "idVendor");
        const std::string pid = id_of(r, "idProduct");
        EXPECT_TRUE(std::regex_match(vid, hex4)) << where << ": idVendor \"" << vid << "\" is not lower-case hex";
        EXPECT_TRUE(std::regex_match(pid, hex4)) << where << ": idProduct \"" << pid << "\" is not lower-case hex";
        EXPECT_FALSE(r.get("SUBSYSTEM").empty()) << where << ": no SUBSYSTEM match";
        if (std::regex_match(vid, hex4) && std::regex_match(pid, hex4)) {
            const auto id = find_usb_id(static_cast<std::uint16_t>(std::stoul(vid, nullptr, 16)),
                                        static_cast<std::uint16_t>(std::stoul(pid, nullptr, 16)));
            EXPECT_TRUE(id.has_value()) << where << ": " << vid << ":" << pid << " is not in the ID table";
        }
        auto [b, e] = r.keys.equal_range("MODE");
        for (auto it = b; it != e; ++it) {
            const unsigned long mode = std::stoul(it->second.second, nullptr, 8);
            EXPECT_EQ(mode & 07UL, 0UL) << where << ": MODE=" << it->second.second << " gives access to everyone";
        }
        EXPECT_EQ(r.keys.count("OWNER"), 0U) << where << ": no OWNER=: access goes to the seat user or a group";
    }
}

/// The rule granting access to `id` over its link's subsystem, or nullptr.
const Rule* rule_for(const std::vector<Rule>& rules, const UsbId& id) {
    for (const Rule& r : rules) {
        if (r.get("SUBSYSTEM") == subsystem_for(id.link) && id_of(r, "idVendor") == hex4(id.vid) &&
            id_of(r, "idProduct") == hex4(id.pid)) {
            return &r;
        }
    }
    return nullptr;
}

TEST(UdevRules, UaccessRulesCoverTheIdTable) {
    const std::string path = std::string(BALLBAR_UDEV_DIR) + "/70-ballbar.rules";
    const auto rules = parse_rules(path);
    check_common(path, rules);
    ASSERT_FALSE(usb_ids().empty());
    for (const UsbId& id : usb_ids()) {
        const Rule* r = rule_for(rules, id);
        ASSERT_NE(r, nullptr) << path << ": no " << subsystem_for(id.link) << " rule for " << hex4(id.vid) << ":"
                              << hex4(id.pid) << " (" << id.model << ")";
        EXPECT_TRUE(r->has("TAG", "+=", "uaccess")) << path << ":" << r->line << ": no TAG+=\"uaccess\"";
        EXPECT_EQ(r->keys.count("MODE"), 0U) << path << ":" << r->line << ": the uaccess rules set no MODE";
    }
    // the vendor interface needs the usbfs node; HID also gets it for hidapi's libusb backend
    EXPECT_EQ(rules.size(), usb_ids().size() + 1);
}

TEST(UdevRules, PlugdevVariantCoversTheIdTable) {
    const std::string path = std::string(BALLBAR_UDEV_DIR) + "/plugdev/70-ballbar.rules";
    const auto rules = parse_rules(path);
    check_common(path, rules);
    for (const UsbId& id : usb_ids()) {
        const Rule* r = rule_for(rules, id);
        ASSERT_NE(r, nullptr) << path << ": no rule for " << hex4(id.vid) << ":" << hex4(id.pid);
        EXPECT_TRUE(r->has("MODE", "=", "0660")) << path << ":" << r->line;
        EXPECT_TRUE(r->has("GROUP", "=", "plugdev")) << path << ":" << r->line;
    }
}

TEST(UdevRules, RulesFilesSortBeforeSeatLate) {
    // TAG+="uaccess" only works if applied before 73-seat-late.rules turns it into an ACL
    int files = 0;
    for (const char* dir : {"", "/plugdev"}) {
        for (const auto& e : std::filesystem::directory_iterator(std::string(BALLBAR_UDEV_DIR) + dir)) {
            if (e.path().extension() != ".rules") continue;
            ++files;
            EXPECT_LT(e.path().filename().string(), "73-seat-late.rules") << e.path();
        }
    }
    EXPECT_EQ(files, 4);  // the instrument's rules and the gauges', each in both variants
}

std::string read_text(const std::string& path) {
    std::ifstream in(path);
    EXPECT_TRUE(in) << "cannot read " << path;
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

TEST(UdevRules, GaugeRulesAreGeneratedFromTheGaugeIdTable) {
    // The committed files are exactly what the table gives (regenerate: ballbar udev-rules [--plugdev]).
    for (const bool plugdev : {false, true}) {
        const std::string path =
            std::string(BALLBAR_UDEV_DIR) + (plugdev ? "/plugdev" : "") + "/70-ballbar-gauges.rules";
        EXPECT_EQ(read_text(path), gauge_udev_rules(plugdev))
            << path << " is stale: run `ballbar udev-rules" << (plugdev ? " --plugdev" : "") << " > " << path << "`";
        const auto rules = parse_rules(path);
        ASSERT_EQ(rules.size(), gauge_usb_ids().size()) << path;
        for (const GaugeUsbId& id : gauge_usb_ids()) {
            const Rule* found = nullptr;
            for (const Rule& r : rules)
                if (r.get("SUBSYSTEM") == id.subsystem && id_of(r, "idVendor") == hex4(id.vid) &&
                    id_of(r, "idProduct") == hex4(id.pid))
                    found = &r;
            ASSERT_NE(found, nullptr) << path << ": no rule for " << hex4(id.vid) << ":" << hex4(id.pid);
            if (plugdev) {
                EXPECT_TRUE(found->has("MODE", "=", "0660"));
                EXPECT_TRUE(found->has("GROUP", "=", "plugdev"));
            } else {
                EXPECT_TRUE(found->has("TAG", "+=", "uaccess"));
                EXPECT_EQ(found->keys.count("MODE"), 0U);
            }
            EXPECT_EQ(found->keys.count("OWNER"), 0U);
        }
    }
}

TEST(UsbIds, GaugeTableHasTheItnAndNoneOfOurs) {
    const auto itn = find_gauge_usb_id(0x0fe7, 0x4001);
    ASSERT_TRUE(itn.has_value());
    EXPECT_STREQ(itn->scheme, "mitutoyo-itn");
    for (const GaugeUsbId& g : gauge_usb_ids()) {
        EXPECT_FALSE(find_usb_id(g.vid, g.pid).has_value()) << "a gauge ID in the instrument table";
        EXPECT_TRUE(std::string(g.subsystem) == "usb" || std::string(g.subsystem) == "tty");
    }
}

TEST(UsbIds, TableIsConsistent) {
    const auto ids = usb_ids();
    ASSERT_EQ(ids.size(), 3U);
    for (std::size_t i = 0; i < ids.size(); ++i) {
        EXPECT_EQ(ids[i].vid, kBallbarVendorId);
        for (std::size_t j = i + 1; j < ids.size(); ++j) {
            EXPECT_NE(ids[i].pid, ids[j].pid) << "two links share a product ID";
            EXPECT_NE(ids[i].link, ids[j].link);
        }
        EXPECT_EQ(find_usb_id(ids[i].vid, ids[i].pid)->link, ids[i].link);
        EXPECT_EQ(usb_id_for(ids[i].link).pid, ids[i].pid);
    }
    EXPECT_FALSE(find_usb_id(0x1209, 0xffff).has_value());
    EXPECT_EQ(hex4(0xB0B0), "b0b0");
    EXPECT_EQ(hex4(0x0001), "0001");
}

}  // namespace
}  // namespace ballbar::device
