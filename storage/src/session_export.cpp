// SPDX-License-Identifier: MIT
#include "ballbar/storage/session_export.hpp"

#include <charconv>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "ballbar/analysis/sample.hpp"
#include "ballbar/fileio/output.hpp"
#include "ballbar/storage/machine_json.hpp"

namespace ballbar::storage {
namespace {

using ojson = nlohmann::ordered_json;

ojson parse_or_text(const std::string& text) {
    if (text.empty()) return nullptr;
    auto j = ojson::parse(text, nullptr, false);
    return j.is_discarded() ? ojson(text) : j;
}

template <class T>
ojson opt(const std::optional<T>& v) {
    return v ? ojson(*v) : ojson(nullptr);
}

/// A text, or null when empty (docs/cli.md's vocabulary has no "").
ojson text(const std::string& s) {
    return s.empty() ? ojson(nullptr) : ojson(s);
}

ojson session_header(const SessionInfo& s) {
    ojson j;
    j["id"] = s.id;
    j["uuid"] = s.uuid;
    j["state"] = std::string(to_string(s.state));
    j["state_reason"] = text(s.reason);
    j["resumable"] = s.resumable();
    j["source"] = std::string(to_string(s.source));
    j["operator"] = text(s.operator_name);
    j["procedure"] = text(s.procedure);
    j["notes"] = text(s.notes);
    j["started_at"] = s.started_at;
    j["ended_at"] = opt(s.ended_at);
    j["machine"] = ojson::parse(machine_to_json(s.machine));
    j["machine_asset_id"] = s.machine_asset.empty() ? ojson(nullptr) : ojson(s.machine_asset);
    j["instrument"] = s.instrument ? ojson::parse(instrument_to_json(*s.instrument)) : ojson(nullptr);
    j["metadata"] = parse_or_text(s.metadata_json);
    j["sample_count"] = s.sample_count;
    j["point_count"] = s.point_count;
    return j;
}

ojson point_json(const PointRecord& p) {
    const auto& r = p.reading;
    ojson j;
    j["index"] = p.index;
    j["location"] = r.location;
    j["point"] = r.point;
    j["step"] = r.step;
    j["X_mm"] = r.pose.X_mm;
    j["Y_mm"] = r.pose.Y_mm;
    j["Z_mm"] = r.pose.Z_mm;
    j["A_rad"] = r.pose.A_rad;
    j["B_rad"] = r.pose.B_rad;
    j["C_rad"] = r.pose.C_rad;
    j["socket_mm"] = {r.socket_mm.x(), r.socket_mm.y(), r.socket_mm.z()};
    j["nominal_mm"] = p.nominal_mm;
    j["measured_mm"] = r.measured_mm;
    j["sd_mm"] = opt(r.std_mm);  // the readings' spread, not an uncertainty
    j["n"] = r.n;
    j["first_seq"] = opt(p.first_seq);
    j["last_seq"] = opt(p.last_seq);
    j["time_s"] = r.time_s;
    j["bar_temp_C"] = opt(r.bar_temp_C);
    j["air_temp_C"] = opt(r.air_temp_C);
    j["machine_temp_C"] = opt(r.machine_temp_C);
    return j;
}

std::string num(double v) {
    char buf[40];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

template <class T>
std::string opt_num(const std::optional<T>& v) {
    if (!v) return {};
    if constexpr (std::is_floating_point_v<T>) {
        return num(*v);
    } else {
        return std::to_string(*v);
    }
}

}  // namespace

std::string session_json(Store& store, std::int64_t id, bool with_points, int indent) {
    const SessionInfo s = store.session(id);
    ojson doc;
    doc["format"] = "ballbar-session/1";
    doc["session"] = session_header(s);
    ojson transitions = ojson::array();
    for (const auto& t : store.transitions(id)) {
        transitions.push_back({{"from", t.from ? ojson(std::string(to_string(*t.from))) : ojson(nullptr)},
                               {"to", std::string(to_string(t.to))},
                               {"event", t.event},
                               {"at", t.at}});
    }
    doc["transitions"] = transitions;
    ojson procedure = ojson::array();
    for (const auto& p : store.procedure_steps(id)) {
        procedure.push_back(
            {{"from", p.from}, {"to", p.to}, {"event", p.event}, {"detail", text(p.detail)}, {"at", p.at}});
    }
    doc["procedure"] = procedure;
    ojson segments = ojson::array();
    for (const auto& g : store.sample_segments(id)) {
        segments.push_back({{"first_seq", g.first_seq},
                            {"device_time_us", g.device_time_us},
                            {"started_at", g.started_at},
                            {"resolution_mm", opt(g.resolution_mm)},
                            {"reading_rate_hz", opt(g.reading_rate_hz)}});
    }
    doc["sample_segments"] = segments;
    ojson gaps = ojson::array();
    for (const auto& g : store.sample_gaps(id))
        gaps.push_back({{"before_seq", g.before_seq}, {"duration_s", opt(g.duration_s)}, {"cause", g.cause}});
    doc["sample_gaps"] = gaps;
    if (with_points) {
        ojson points = ojson::array();
        for (const auto& p : store.points(id)) points.push_back(point_json(p));
        doc["points"] = points;
    }
    ojson results = ojson::array();
    std::set<std::int64_t> model_ids;
    for (const auto& r : store.results(id)) {
        results.push_back({{"id", r.id},
                           {"kind", r.kind},
                           {"model_id", opt(r.model_id)},
                           {"producer", r.producer},
                           {"created_at", r.created_at},
                           {"payload", parse_or_text(r.payload_json)}});
        if (r.model_id) model_ids.insert(*r.model_id);
    }
    doc["results"] = results;
    ojson models = ojson::array();
    for (const auto mid : model_ids) {
        const auto m = store.model(mid);
        models.push_back({{"id", m.id},
                          {"name", m.name},
                          {"version", m.version},
                          {"parent_id", opt(m.parent_id)},
                          {"created_at", m.created_at},
                          {"session_ids", m.session_ids},
                          {"notes", text(m.notes)},
                          {"params", parse_or_text(m.params_json)}});
    }
    doc["models"] = models;
    return doc.dump(indent);
}

std::string sessions_json(Store& store, int indent) {
    ojson list = ojson::array();
    for (const auto& s : store.sessions()) list.push_back(session_header(s));
    return list.dump(indent);
}

void write_points_csv(Store& store, std::int64_t id, std::ostream& out) {
    out << "index,location,point,step,X_mm,Y_mm,Z_mm,A_deg,B_deg,C_deg,socket_x_mm,socket_y_mm,socket_z_mm,"
           "nominal_mm,measured_mm,std_mm,n,first_seq,last_seq,time_s,bar_temp_C,air_temp_C,machine_temp_C\n";
    for (const auto& p : store.points(id)) {
        const auto& r = p.reading;
        out << p.index << ',' << (r.location >= 0 ? std::to_string(r.location) : "") << ','
            << (r.point >= 0 ? std::to_string(r.point) : "") << ',' << (r.step > 0 ? std::to_string(r.step) : "") << ','
            << num(r.pose.X_mm) << ',' << num(r.pose.Y_mm) << ',' << num(r.pose.Z_mm) << ','
            << num(analysis::rad_to_deg(r.pose.A_rad)) << ',' << num(analysis::rad_to_deg(r.pose.B_rad)) << ','
            << num(analysis::rad_to_deg(r.pose.C_rad)) << ',' << num(r.socket_mm.x()) << ',' << num(r.socket_mm.y())
            << ',' << num(r.socket_mm.z()) << ',' << num(p.nominal_mm) << ',' << num(r.measured_mm) << ','
            << opt_num(r.std_mm) << ',' << (r.n > 0 ? std::to_string(r.n) : "") << ',' << opt_num(p.first_seq) << ','
            << opt_num(p.last_seq) << ',' << num(r.time_s) << ',' << opt_num(r.bar_temp_C) << ','
            << opt_num(r.air_temp_C) << ',' << opt_num(r.machine_temp_C) << '\n';
    }
}

void write_samples_csv(Store& store, std::int64_t id, std::ostream& out) {
    out << "seq,device_time_us,displacement_nm,flags,bar_temp_C\n";
    std::string line;
    store.for_each_sample(id, [&](const analysis::BarSample& s) {
        line.clear();
        line += std::to_string(s.seq);
        line += ',';
        line += std::to_string(s.device_time_us);
        line += ',';
        line += std::to_string(s.displacement_nm);
        line += ',';
        line += std::to_string(s.flags);
        line += ',';
        if (!(s.flags & analysis::kSampleTempInvalid))  // an empty cell: the sample has no bar temperature
            line += num(static_cast<double>(std::lround(static_cast<double>(s.bar_temp_C) * 1000.0)) / 1000.0);
        line += '\n';
        out << line;
    });
}

void export_csv(Store& store, std::int64_t id, const std::filesystem::path& dir) {
    store.session(id);  // not_found before creating anything
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw std::runtime_error("cannot create " + dir.string() + ": " + ec.message());
    export_csv_files(store, id, dir / "points.csv", dir / "samples.csv");
}

void export_csv_files(Store& store, std::int64_t id, const std::filesystem::path& points_path,
                      const std::filesystem::path& samples_path) {
    store.session(id);  // not_found before writing anything
    // fileio: exclusive temporary files, no links. Both are written in full before either replaces
    // anything: a full disk or a damaged database half-way leaves the files as they were, never a new
    // points file beside an old samples file.
    fileio::OutputStream points(points_path.string(), "--out");
    fileio::OutputStream samples(samples_path.string(), "--out");
    write_points_csv(store, id, points);
    write_samples_csv(store, id, samples);
    points.finish();
    samples.finish();
    samples.commit();
    points.commit();
}

}  // namespace ballbar::storage
