// SPDX-License-Identifier: MIT
#include "ballbar/analysis/plan_identification.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>

#include "ballbar/analysis/identify.hpp"
#include "ballbar/analysis/kinematics.hpp"

namespace ballbar::analysis {
namespace {

std::vector<double> angle_range(double from_deg, double to_deg, double step_deg) {
    std::vector<double> out;
    for (double a = from_deg; a <= to_deg + 1e-9; a += step_deg) out.push_back(deg_to_rad(a));
    return out;
}

std::vector<Vec3> default_sockets(const MachineGeometry& geom) {
    switch (geom.type) {
        case MachineType::RRTTT:  // machine frame; the head turns about its pivot
            return {geom.tool_ball_mm + Vec3(0, 0, -100), geom.tool_ball_mm + Vec3(150, 50, -100)};
        case MachineType::TTTRR:
        case MachineType::RTTTR:  // table frame
            return {Vec3(100, 0, 20), Vec3(-60, 80, 20)};
    }
    return {Vec3::Zero()};
}

// Σ log(independence) over the columns in `cols` of the accumulated Gram matrix, and the minimum
// over the first `goal` of them.
struct Score {
    double log_sum = -std::numeric_limits<double>::infinity();
    double min_goal = 0;
    Eigen::VectorXd indep;
};

Score score(const Eigen::MatrixXd& gram, const std::vector<int>& cols, std::size_t goal) {
    const auto n = static_cast<Eigen::Index>(cols.size());
    Eigen::MatrixXd a(n, n);
    Eigen::VectorXd d(n);
    for (Eigen::Index i = 0; i < n; ++i)
        d[i] = std::sqrt(gram(cols[static_cast<std::size_t>(i)], cols[static_cast<std::size_t>(i)]));
    for (Eigen::Index i = 0; i < n; ++i)
        for (Eigen::Index j = 0; j < n; ++j) {
            const double dij = d[i] * d[j];
            a(i, j) = dij > 0 ? gram(cols[static_cast<std::size_t>(i)], cols[static_cast<std::size_t>(j)]) / dij : 0.0;
        }
    a.diagonal().array() += 1e-10;  // regularised: unobservable columns score ~1e-5, not NaN
    const Eigen::MatrixXd inv = a.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
    Score s;
    s.indep.resize(n);
    s.log_sum = 0;
    s.min_goal = 1;
    for (Eigen::Index i = 0; i < n; ++i) {
        const double v = inv(i, i) > 0 ? 1.0 / std::sqrt(inv(i, i)) : 0.0;
        s.indep[i] = d[i] > 0 ? std::min(v, 1.0) : 0.0;
        s.log_sum += std::log(std::max(s.indep[i], 1e-8));
        if (static_cast<std::size_t>(i) < goal) s.min_goal = std::min(s.min_goal, s.indep[i]);
    }
    return s;
}

}  // namespace

std::size_t IdentificationPlan::readings() const {
    std::size_t n = 0;
    for (const auto& l : locations) n += l.points.size();
    return n;
}

PlannedLocation ssm_location(const MachineGeometry& geom, const Pose& rotary, const Vec3& socket_mm,
                             double bar_length_mm, double cone_half_angle_rad, int points) {
    PlannedLocation loc;
    loc.rotary = rotary;
    loc.rotary.X_mm = loc.rotary.Y_mm = loc.rotary.Z_mm = 0;
    loc.socket_mm = socket_mm;
    const Vec3 s = nominal_table_ball(geom, loc.rotary, socket_mm);
    for (int k = 0; k < points; ++k) {
        const double az = 2.0 * kPi * k / points;
        const Vec3 dir(std::sin(cone_half_angle_rad) * std::cos(az), std::sin(cone_half_angle_rad) * std::sin(az),
                       std::cos(cone_half_angle_rad));
        loc.points.push_back(command_for_tool_ball(geom, loc.rotary, s + bar_length_mm * dir));
    }
    return loc;
}

ReadingSet plan_readings(const MachineGeometry& geom, const IdentificationPlan& plan) {
    ReadingSet out;
    out.machine = geom;
    for (std::size_t l = 0; l < plan.locations.size(); ++l) {
        const auto& loc = plan.locations[l];
        for (std::size_t p = 0; p < loc.points.size(); ++p) {
            Reading r;
            r.pose = loc.points[p];
            r.socket_mm = loc.socket_mm;
            r.measured_mm = nominal_length(geom, r.pose, loc.socket_mm);
            r.location = static_cast<int>(l);
            r.point = static_cast<int>(p);
            out.readings.push_back(r);
        }
    }
    return out;
}

IdentificationPlan plan_identification(const MachineGeometry& geom, const PlanOptions& opt) {
    if (opt.params.empty()) throw AnalysisError("plan: no parameters to make observable");
    if (!(opt.bar_length_mm > 0)) throw AnalysisError("plan: bar length must be positive");
    if (opt.points_per_location < 1) throw AnalysisError("plan: at least one point per location");
    if (!(opt.min_readings_per_unknown >= 1)) throw AnalysisError("plan: min_readings_per_unknown must be >= 1");
    const std::vector<Vec3> sockets = opt.sockets_mm.empty() ? default_sockets(geom) : opt.sockets_mm;
    const bool second_is_c = geom.type == MachineType::TTTRR;
    const std::vector<double> first = opt.first_angles_rad.empty() ? angle_range(-90, 90, 15) : opt.first_angles_rad;
    const std::vector<double> second = !opt.second_angles_rad.empty() ? opt.second_angles_rad
                                       : second_is_c                  ? angle_range(0, 330, 30)
                                                                      : angle_range(-90, 90, 15);
    const RotaryAxes axes = rotary_axes(geom.type);
    IdentificationPlan candidates;
    for (const Vec3& s : sockets)
        for (double a : first)
            for (double b : second) {
                Pose rot;
                rot.A_rad = a;
                if (axes.second == 'C')
                    rot.C_rad = b;
                else
                    rot.B_rad = b;
                candidates.locations.push_back(
                    ssm_location(geom, rot, s, opt.bar_length_mm, opt.cone_half_angle_rad, opt.points_per_location));
            }
    if (candidates.locations.empty()) throw AnalysisError("plan: no candidate locations");

    // Jacobian of every candidate reading at the nominal machine; per-candidate Gram blocks.
    const ReadingSet all = plan_readings(geom, candidates);
    const ErrorParams zero{};
    const Eigen::MatrixXd jac = reading_jacobian(all, zero, opt.params, {}, opt.fit_socket_offsets);
    const auto np = static_cast<Eigen::Index>(opt.params.size());
    const Eigen::Index n = jac.cols();

    // Reachability: with every candidate measured, which parameters can be determined at all?
    Eigen::VectorXd norms = jac.colwise().norm().transpose();
    Eigen::MatrixXd unit = jac;
    for (Eigen::Index c = 0; c < n; ++c)
        if (norms[c] > 1e-12 * std::sqrt(static_cast<double>(jac.rows())))
            unit.col(c) /= norms[c];
        else
            unit.col(c).setZero();
    std::vector<int> order;
    for (Eigen::Index c = np; c < n; ++c) order.push_back(static_cast<int>(c));
    for (Eigen::Index c = 0; c < np; ++c) order.push_back(static_cast<int>(c));
    std::vector<int> accepted;
    const Eigen::VectorXd reach = sequential_independence(unit.transpose() * unit, order, 1e-4, accepted);

    IdentificationPlan plan;
    std::vector<int> goal_cols;  // parameter columns that can be reached
    for (Eigen::Index c = 0; c < np; ++c) {
        const Param p = opt.params[static_cast<std::size_t>(c)];
        plan.params.push_back({p, 0, false});
        if (reach[c] >= 1e-4)
            goal_cols.push_back(static_cast<int>(c));
        else
            plan.unreachable.push_back(std::string(param_info(p).name) +
                                       (norms[c] <= 1e-12
                                            ? ": no effect on any candidate reading"
                                            : ": not separable from the socket offsets and the parameters before it"));
    }

    const std::size_t rows_per = static_cast<std::size_t>(opt.points_per_location);
    std::vector<bool> used(candidates.locations.size(), false);
    std::vector<bool> socket_used(sockets.size(), false);
    Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(n, n);
    auto block_gram = [&](std::size_t cand) {
        const auto rows =
            jac.middleRows(static_cast<Eigen::Index>(cand * rows_per), static_cast<Eigen::Index>(rows_per));
        return Eigen::MatrixXd(rows.transpose() * rows);
    };
    auto columns_for = [&](const std::vector<bool>& sock) {
        std::vector<int> cols = goal_cols;
        if (opt.fit_socket_offsets)
            for (std::size_t k = 0; k < sock.size(); ++k)
                if (sock[k])
                    for (int a = 0; a < 3; ++a) cols.push_back(static_cast<int>(np) + 3 * static_cast<int>(k) + a);
        return cols;
    };
    const std::size_t per_socket = candidates.locations.size() / sockets.size();
    Score current;
    while (plan.locations.size() < opt.max_locations) {
        double best = -std::numeric_limits<double>::infinity();
        std::size_t best_c = 0;
        for (std::size_t c = 0; c < candidates.locations.size(); ++c) {
            if (used[c]) continue;
            std::vector<bool> sock = socket_used;
            sock[c / per_socket] = true;
            const Score s = score(gram + block_gram(c), columns_for(sock), goal_cols.size());
            if (s.log_sum > best) {
                best = s.log_sum;
                best_c = c;
            }
        }
        if (!std::isfinite(best)) break;
        used[best_c] = true;
        socket_used[best_c / per_socket] = true;
        gram += block_gram(best_c);
        plan.locations.push_back(candidates.locations[best_c]);
        current = score(gram, columns_for(socket_used), goal_cols.size());
        const std::size_t unknowns = columns_for(socket_used).size();
        if (current.min_goal >= opt.target_independence &&
            static_cast<double>(plan.readings()) >= opt.min_readings_per_unknown * static_cast<double>(unknowns) &&
            plan.readings() > unknowns + 2) {
            plan.sufficient = true;
            break;
        }
    }
    for (std::size_t g = 0; g < goal_cols.size(); ++g) {
        auto& pp = plan.params[static_cast<std::size_t>(goal_cols[g])];
        pp.independence = current.indep.size() > 0 ? current.indep[static_cast<Eigen::Index>(g)] : 0.0;
        pp.observable = pp.independence >= 1e-4;
    }
    return plan;
}

}  // namespace ballbar::analysis
