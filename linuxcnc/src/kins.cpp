// SPDX-License-Identifier: MIT
#include "ballbar/linuxcnc/kins.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "ballbar/analysis/nc_compensate.hpp"
#include "ballbar/storage/model_codec.hpp"

namespace ballbar::linuxcnc {
namespace ba = ballbar::analysis;

namespace {

// The forward kinematics' fixed-point iteration: u = joints − du(u). du changes by |∂du/∂u|·|Δu|
// per step, about 1e-4 of Δu for errors of tens of µm and µrad over a lever of a few hundred mm.
constexpr int kForwardIterations = 8;
constexpr double kForwardTolerance = 1e-12;

ba::Pose to_pose(const Axes& a) {
    ba::Pose p;
    p.X_mm = a[0];
    p.Y_mm = a[1];
    p.Z_mm = a[2];
    p.A_rad = ba::deg_to_rad(a[3]);
    p.C_rad = ba::deg_to_rad(a[4]);
    return p;
}

// The tool point seen from the commanded XYZ: LinuxCNC's tool-length offset, along −Z.
ba::Vec3 tool_vector(double tool_offset_mm) {
    return {0, 0, -tool_offset_mm};
}

// The nominal joints of a world position (TCP type): the tool tip is the world point less the
// tool offset; the joints put the spindle's reference point the tool length above it.
Axes nominal_tcp_inverse(const ba::MachineGeometry& g, const Axes& world, double tool_offset_mm) {
    const ba::Vec3 t = tool_vector(tool_offset_mm);
    const ba::Vec3 tip = ba::Vec3(world[0], world[1], world[2]) + t;
    const ba::Vec3 m = ba::tcp_inverse(g, tip, ba::deg_to_rad(world[3]), ba::deg_to_rad(world[4])) - t;
    return {m.x(), m.y(), m.z(), world[3], world[4]};
}

Axes nominal_tcp_forward(const ba::MachineGeometry& g, const Axes& joints, double tool_offset_mm) {
    const ba::Vec3 t = tool_vector(tool_offset_mm);
    const ba::Vec3 tip = ba::tcp_forward(g, ba::Vec3(joints[0], joints[1], joints[2]) + t, ba::deg_to_rad(joints[3]),
                                         ba::deg_to_rad(joints[4]));
    const ba::Vec3 w = tip - t;
    return {w.x(), w.y(), w.z(), joints[3], joints[4]};
}

}  // namespace

std::uint32_t fnv1a(std::string_view bytes) {
    std::uint32_t h = 2166136261u;
    for (const char c : bytes) {
        h ^= static_cast<unsigned char>(c);
        h *= 16777619u;
    }
    return h;
}

ba::CompensationOptions module_compensation_options() {
    ba::CompensationOptions o;
    o.singular_tolerance = ba::default_singular_tolerance();
    o.max_rotary_step_rad = ba::deg_to_rad(0.1);
    return o;
}

CompensatingKins::CompensatingKins(const ba::MachineGeometry& geometry, const ba::ErrorParams& errors,
                                   std::vector<ba::LearnedTerm> terms)
    : geometry_(geometry), compensator_(geometry, errors, terms, module_compensation_options()) {
    if (geometry.type != ba::MachineType::TTTRR)
        throw KinsLoadError("the model is of a " + std::string(ba::to_string(geometry.type)) +
                            " machine; ballbarkins drives table-tilting XYZAC machines (TTTRR) only");
}

CompensatingKins CompensatingKins::from_model_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw KinsLoadError("cannot open the model file '" + path + "'");
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw KinsLoadError("cannot read the model file '" + path + "'");
    const std::string bytes = text.str();
    storage::ErrorModel model;
    try {
        model = storage::model_from_json(bytes);
    } catch (const std::exception& e) {  // the codec's FormatError and the JSON parser's own errors
        throw KinsLoadError("the model file '" + path + "' is not a ballbar-model/1: " + e.what());
    }
    try {
        CompensatingKins k(model.machine, model.values(), model.empirical);
        k.hash_ = fnv1a(bytes);
        return k;
    } catch (const KinsLoadError& e) {
        throw KinsLoadError("the model file '" + path + "': " + e.what());
    }
}

Axes CompensatingKins::correction(const ba::Pose& u, const ba::Vec3& tool_mm, bool& singular) const {
    const ba::Correction c = compensator_.first_order(u, tool_mm);
    singular = c.singular;
    return {c.du[0], c.du[1], c.du[2], ba::rad_to_deg(c.du[3]), ba::rad_to_deg(c.du[4])};
}

InverseResult CompensatingKins::inverse(KinsType type, const Axes& world, double tool_offset_mm,
                                        bool enable) const noexcept {
    InverseResult r;
    const Axes u = type == KinsType::tcp ? nominal_tcp_inverse(geometry_, world, tool_offset_mm) : world;
    if (enable) r.correction = correction(to_pose(u), tool_vector(tool_offset_mm), r.singular);
    for (std::size_t i = 0; i < 5; ++i) r.joints[i] = u[i] + r.correction[i];
    return r;
}

Axes CompensatingKins::forward(KinsType type, const Axes& joints, double tool_offset_mm, bool enable) const noexcept {
    Axes u = joints;
    if (enable) {
        const ba::Vec3 t = tool_vector(tool_offset_mm);
        for (int k = 0; k < kForwardIterations; ++k) {
            bool singular = false;
            const Axes du = correction(to_pose(u), t, singular);
            double change = 0;
            for (std::size_t i = 0; i < 5; ++i) {
                const double next = joints[i] - du[i];
                change = std::max(change, std::abs(next - u[i]));
                u[i] = next;
            }
            if (change <= kForwardTolerance) break;
        }
    }
    return type == KinsType::tcp ? nominal_tcp_forward(geometry_, u, tool_offset_mm) : u;
}

XyzacTrtSettings CompensatingKins::xyzac_equivalent() const {
    // xyzac-trt-kins: joints = Rx(A)·(Rz(C)·(w − r) − d) + d + r, d = (0, y-offset, z-offset); ours:
    // joints = a_pivot + Rx(A)·(c_offset + Rz(C)·(w − a_pivot − c_offset)). So r = a_pivot + c_offset
    // and d = −c_offset (its x has no effect: Rx keeps x).
    const ba::Vec3 r = geometry_.a_pivot_mm + geometry_.c_offset_mm;
    return {r.x(), r.y(), r.z(), -geometry_.c_offset_mm.y(), -geometry_.c_offset_mm.z()};
}

}  // namespace ballbar::linuxcnc
