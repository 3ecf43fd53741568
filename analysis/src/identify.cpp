// SPDX-License-Identifier: MIT
#include "ballbar/analysis/identify.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/analysis/reading_model.hpp"

namespace ballbar::analysis {
namespace {

constexpr double kSocketMatchMm = 1e-6;

const char* const kAxisNames[3] = {"x", "y", "z"};

}  // namespace

std::string FitOptions::validate() const {
    std::vector<bool> seen(kParamCount, false);
    for (Param p : free_params) {
        const auto i = static_cast<std::size_t>(p);
        if (i >= kParamCount) return "free parameter out of range";
        if (seen[i]) return "parameter " + std::string(param_info(p).name) + " listed twice";
        seen[i] = true;
    }
    if (max_iterations < 1) return "max_iterations must be at least 1";
    if (!(min_independence > 0 && min_independence < 1)) return "min_independence must be in (0, 1)";
    if (!(min_sensitivity >= 0)) return "min_sensitivity must be >= 0";
    if (!(step_tolerance > 0)) return "step_tolerance must be > 0";
    return {};
}

std::vector<std::string> FitSummary::unobservable() const {
    std::vector<std::string> out;
    for (const auto& e : estimates)
        if (!e.observable) out.push_back(e.name);
    return out;
}

const ParamEstimate* FitSummary::find(std::string_view name) const {
    for (const auto& e : estimates)
        if (e.name == name) return &e;
    return nullptr;
}

std::string FitSummary::brief_report() const {
    std::ostringstream os;
    os << (converged ? "converged" : "NOT converged") << " after " << iterations << " iterations (" << message << "); "
       << readings << " readings, residual RMS " << residual_rms_mm * 1000.0 << " um (start " << initial_rms_mm * 1000.0
       << " um)\n";
    for (const auto& e : estimates) {
        os << "  " << e.name << ": ";
        if (e.observable)
            os << e.estimate << " +- " << e.std << " (independence " << e.independence << ")\n";
        else
            os << "unobservable (independence " << e.independence << "), held at " << e.estimate << "\n";
    }
    return os.str();
}

std::vector<SocketPosition> socket_positions(const ReadingSet& readings, std::vector<int>* reading_socket) {
    std::vector<SocketPosition> out;
    if (reading_socket) reading_socket->assign(readings.readings.size(), -1);
    for (std::size_t i = 0; i < readings.readings.size(); ++i) {
        const Vec3& s = readings.readings[i].socket_mm;
        int found = -1;
        for (std::size_t k = 0; k < out.size(); ++k)
            if ((out[k].nominal_mm - s).cwiseAbs().maxCoeff() <= kSocketMatchMm) {
                found = static_cast<int>(k);
                break;
            }
        if (found < 0) {
            out.push_back({s, Vec3::Zero(), 0});
            found = static_cast<int>(out.size() - 1);
        }
        ++out[static_cast<std::size_t>(found)].readings;
        if (reading_socket) (*reading_socket)[i] = found;
    }
    return out;
}

namespace {

std::string format_vec(const Vec3& v) {
    std::ostringstream os;
    os.precision(10);
    os << '[' << v.x() << ", " << v.y() << ", " << v.z() << "] mm";
    return os.str();
}

/// Readings are merged for one fit only when they are of one machine: its type, and the geometry the
/// model computes with (a set of another geometry would be fitted with the first set's, silently wrong).
void check_same_machine(const MachineGeometry& a, const MachineGeometry& b) {
    if (b.type != a.type)
        throw AnalysisError("cannot merge readings of a " + std::string(to_string(b.type)) +
                            " machine with readings of a " + std::string(to_string(a.type)) + " machine");
    constexpr double kSame_mm = 1e-6;  // a machine file written and read again agrees to far better
    const std::pair<const char*, Vec3 MachineGeometry::*> keys[] = {{"tool_ball_mm", &MachineGeometry::tool_ball_mm},
                                                                    {"a_pivot_mm", &MachineGeometry::a_pivot_mm},
                                                                    {"c_offset_mm", &MachineGeometry::c_offset_mm}};
    for (const auto& [key, member] : keys) {
        // Only what the type's kinematics use (machine_json.hpp's rule): the rest is not the machine's.
        const std::string_view k = key;
        if (k == "a_pivot_mm" && a.type == MachineType::RRTTT) continue;
        if (k == "c_offset_mm" && a.type != MachineType::TTTRR) continue;
        if (((a.*member) - (b.*member)).cwiseAbs().maxCoeff() > kSame_mm)
            throw AnalysisError(std::string("cannot merge readings of two machines: their ") + key + " differ (" +
                                format_vec(a.*member) + " and " + format_vec(b.*member) + ")");
    }
}

}  // namespace

ReadingSet merge_readings(std::span<const ReadingSet> sets) {
    if (sets.empty()) throw AnalysisError("no readings to merge");
    ReadingSet out;
    out.machine = sets.front().machine;
    for (const auto& s : sets) {
        check_same_machine(out.machine, s.machine);
        out.readings.insert(out.readings.end(), s.readings.begin(), s.readings.end());
    }
    return out;
}

ReadingSet merge_readings(std::vector<ReadingSet>&& sets) {
    if (sets.empty()) throw AnalysisError("no readings to merge");
    for (const auto& s : sets) check_same_machine(sets.front().machine, s.machine);
    ReadingSet out = std::move(sets.front());
    std::size_t total = 0;
    for (const auto& s : sets) total += s.readings.size();
    out.readings.reserve(total);
    for (std::size_t k = 1; k < sets.size(); ++k) {
        out.readings.insert(out.readings.end(), sets[k].readings.begin(), sets[k].readings.end());
        std::vector<Reading>().swap(sets[k].readings);  // freed as it goes
    }
    sets.clear();
    return out;
}

ReadingConditions conditions_of(const Reading& r) {
    return {r.time_s, r.bar_temp_C.value_or(20.0)};
}

namespace {

/// What every evaluation of the model over one set of readings shares: the socket position each
/// reading uses and the sines and cosines of its rotary angles. A fit evaluates the model a dozen
/// times; computed once, these were a quarter of the evaluations' cost.
struct PreparedReadings {
    std::vector<int> which;  ///< socket index of each reading (filled by the sockets' initialiser)
    std::vector<SocketPosition> sockets;
    std::vector<ReadingModel::RotaryTrig> trig;

    explicit PreparedReadings(const ReadingSet& readings) : sockets(socket_positions(readings, &which)) {
        trig.reserve(readings.readings.size());
        for (const Reading& r : readings.readings) trig.emplace_back(r.pose);
    }
};

Eigen::VectorXd residuals(const ReadingSet& readings, const PreparedReadings& prep, const ErrorParams& e,
                          std::span<const Vec3> socket_offsets_mm) {
    if (!socket_offsets_mm.empty() && socket_offsets_mm.size() != prep.sockets.size())
        throw AnalysisError("socket offsets: " + std::to_string(socket_offsets_mm.size()) + " given, readings use " +
                            std::to_string(prep.sockets.size()) + " socket positions");
    const ReadingModel model(readings.machine, e);
    Eigen::VectorXd r(static_cast<Eigen::Index>(readings.readings.size()));
    for (std::size_t i = 0; i < readings.readings.size(); ++i) {
        const Reading& rd = readings.readings[i];
        Vec3 socket = rd.socket_mm;
        if (!socket_offsets_mm.empty()) socket += socket_offsets_mm[static_cast<std::size_t>(prep.which[i])];
        r[static_cast<Eigen::Index>(i)] =
            rd.measured_mm - model.predict(rd.pose, prep.trig[i], socket, conditions_of(rd));
    }
    return r;
}

Eigen::MatrixXd jacobian(const ReadingSet& readings, const PreparedReadings& prep, const ErrorParams& e,
                         std::span<const Param> free, std::span<const Vec3> socket_offsets_mm,
                         bool with_socket_offsets) {
    if (!socket_offsets_mm.empty() && socket_offsets_mm.size() != prep.sockets.size())
        throw AnalysisError("socket offsets do not match the readings' socket positions");
    const int np = static_cast<int>(free.size());
    if (free.size() > kParamCount) throw AnalysisError("too many free parameters");
    const auto ns = static_cast<Eigen::Index>(with_socket_offsets ? 3 * prep.sockets.size() : 0);

    // The closed-form gradient (reading_model.hpp); AutoDiff of the templated kinematics is the
    // tests' reference for it.
    const ReadingModel model(readings.machine, e);
    ReadingModel::Gradient grad;
    Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(readings.readings.size()), np + ns);
    for (std::size_t i = 0; i < readings.readings.size(); ++i) {
        const Reading& rd = readings.readings[i];
        const auto k = static_cast<std::size_t>(prep.which[i]);
        Vec3 s = rd.socket_mm;
        if (!socket_offsets_mm.empty()) s += socket_offsets_mm[k];
        model.predict(rd.pose, prep.trig[i], s, conditions_of(rd), &grad);
        const auto row = static_cast<Eigen::Index>(i);
        for (int j = 0; j < np; ++j)
            jac(row, j) = grad.params[static_cast<std::size_t>(free[static_cast<std::size_t>(j)])];
        if (with_socket_offsets)
            for (int a = 0; a < 3; ++a) jac(row, np + 3 * static_cast<Eigen::Index>(k) + a) = grad.socket_mm[a];
    }
    return jac;
}

}  // namespace

Eigen::VectorXd reading_residuals(const ReadingSet& readings, const ErrorParams& e,
                                  std::span<const Vec3> socket_offsets_mm) {
    return residuals(readings, PreparedReadings(readings), e, socket_offsets_mm);
}

Eigen::MatrixXd reading_jacobian(const ReadingSet& readings, const ErrorParams& e, std::span<const Param> free,
                                 std::span<const Vec3> socket_offsets_mm, bool with_socket_offsets) {
    return jacobian(readings, PreparedReadings(readings), e, free, socket_offsets_mm, with_socket_offsets);
}

namespace {

// Column list in priority order (sockets, then parameters in the caller's order), then the greedy test.
std::vector<int> accept_columns(const Eigen::MatrixXd& jac, int np, const FitOptions& opt,
                                std::vector<ParamEstimate>& est) {
    const Eigen::Index n = jac.cols();
    const double rows = static_cast<double>(std::max<Eigen::Index>(jac.rows(), 1));
    const Eigen::VectorXd norms = jac.colwise().norm().transpose();
    std::vector<int> order;
    for (Eigen::Index c = np; c < n; ++c) order.push_back(static_cast<int>(c));
    for (int c = 0; c < np; ++c) order.push_back(c);

    Eigen::MatrixXd scaled = jac;
    for (Eigen::Index c = 0; c < n; ++c) {
        est[static_cast<std::size_t>(c)].sensitivity = norms[c] / std::sqrt(rows);
        if (est[static_cast<std::size_t>(c)].sensitivity > opt.min_sensitivity)
            scaled.col(c) /= norms[c];
        else
            scaled.col(c).setZero();
    }
    std::vector<int> accepted;
    const Eigen::VectorXd indep =
        sequential_independence(scaled.transpose() * scaled, order, opt.min_independence, accepted);
    for (Eigen::Index c = 0; c < n; ++c) est[static_cast<std::size_t>(c)].independence = indep[c];
    std::sort(accepted.begin(), accepted.end());
    return accepted;
}

}  // namespace

Eigen::VectorXd sequential_independence(const Eigen::MatrixXd& unit_gram, std::span<const int> order,
                                        double min_independence, std::vector<int>& accepted) {
    const Eigen::Index n = unit_gram.cols();
    Eigen::VectorXd indep = Eigen::VectorXd::Zero(n);
    Eigen::MatrixXd chol = Eigen::MatrixXd::Zero(n, n);  // Cholesky factor of the accepted columns' Gram
    Eigen::Index m = 0;
    std::vector<int> mine;
    for (int c : order) {
        if (!(unit_gram(c, c) > 0.5)) continue;  // a zero column: no effect at all
        Eigen::VectorXd y(m);
        for (Eigen::Index a = 0; a < m; ++a) y[a] = unit_gram(mine[static_cast<std::size_t>(a)], c);
        if (m > 0) chol.topLeftCorner(m, m).triangularView<Eigen::Lower>().solveInPlace(y);
        const double d = 1.0 - y.squaredNorm();
        indep[c] = std::sqrt(std::max(d, 0.0));
        if (indep[c] < min_independence) continue;
        chol.block(m, 0, 1, m) = y.transpose();
        chol(m, m) = std::sqrt(d);
        mine.push_back(c);
        ++m;
    }
    accepted.insert(accepted.end(), mine.begin(), mine.end());
    return indep;
}

FitSummary fit_error_model(const ReadingSet& readings, const FitOptions& opt) {
    if (const std::string why = opt.validate(); !why.empty()) throw AnalysisError("fit options: " + why);
    FitSummary out;
    const PreparedReadings prep(readings);
    out.sockets = prep.sockets;
    out.readings = readings.readings.size();
    const int np = static_cast<int>(opt.free_params.size());
    const std::size_t ns = opt.fit_socket_offsets ? out.sockets.size() : 0;

    for (Param p : opt.free_params) {
        ParamEstimate pe;
        pe.name = std::string(param_info(p).name);
        pe.param = p;
        pe.estimate = opt.fixed[p];
        out.estimates.push_back(pe);
    }
    for (std::size_t k = 0; k < ns; ++k)
        for (int a = 0; a < 3; ++a) {
            ParamEstimate pe;
            pe.name = "socket" + std::to_string(k) + "." + kAxisNames[a];
            pe.socket = static_cast<int>(k);
            pe.axis = a;
            out.estimates.push_back(pe);
        }
    const std::size_t unknowns = out.estimates.size();
    if (out.readings <= unknowns)
        throw AnalysisError("identification needs more readings than unknowns: " + std::to_string(out.readings) +
                            " readings for " + std::to_string(unknowns) + " unknowns (" + std::to_string(np) +
                            " parameters + " + std::to_string(3 * ns) + " socket offsets)");

    ErrorParams e = opt.fixed;
    std::vector<Vec3> offsets(out.sockets.size(), Vec3::Zero());
    auto measured_minus_predicted = [&](const ErrorParams& ee, const std::vector<Vec3>& off) {
        return residuals(readings, prep, ee, off);
    };
    Eigen::VectorXd r = measured_minus_predicted(e, offsets);
    double cost = r.squaredNorm();
    out.initial_rms_mm = std::sqrt(cost / static_cast<double>(out.readings));

    Eigen::MatrixXd jac_full = jacobian(readings, prep, e, opt.free_params, offsets, opt.fit_socket_offsets);
    const std::vector<int> cols = accept_columns(jac_full, np, opt, out.estimates);
    out.fitted.assign(cols.begin(), cols.end());
    const auto m = static_cast<Eigen::Index>(cols.size());

    auto apply_step = [&](const Eigen::VectorXd& delta, ErrorParams& ee, std::vector<Vec3>& off) {
        for (Eigen::Index j = 0; j < m; ++j) {
            const auto c = static_cast<std::size_t>(cols[static_cast<std::size_t>(j)]);
            const auto& pe = out.estimates[c];
            if (pe.param)
                ee[*pe.param] += delta[j];
            else
                off[static_cast<std::size_t>(pe.socket)][pe.axis] += delta[j];
        }
    };
    auto select = [&](const Eigen::MatrixXd& full) {
        Eigen::MatrixXd j(full.rows(), m);
        for (Eigen::Index k = 0; k < m; ++k) j.col(k) = full.col(cols[static_cast<std::size_t>(k)]);
        return j;
    };

    // Levenberg–Marquardt on unit-scaled columns. The Jacobian is re-evaluated only when the linear
    // model stops predicting the cost reduction (|1 − ρ| > 1e-3) or a step fails: with errors of a
    // few µm on 100 mm bars the model is linear to ~1e-4, so one evaluation usually serves the fit.
    // The unit-scaled Jacobian and its normal matrix change only with the Jacobian: they are formed
    // once per evaluation, not per iteration (the n × m product is most of an iteration's cost).
    Eigen::VectorXd scale;
    Eigen::MatrixXd js, a;
    // Scaled in place and kept as js: at most two n × m matrices live at once (the evaluated Jacobian
    // and its selected columns), 200 MB each for 2 M readings (docs/identification.md, memory).
    auto set_jacobian = [&](Eigen::MatrixXd jac) {
        scale = jac.colwise().norm().transpose();
        for (Eigen::Index k = 0; k < m; ++k)
            if (!(scale[k] > 0)) scale[k] = 1;
        for (Eigen::Index k = 0; k < m; ++k) jac.col(k) /= scale[k];
        js = std::move(jac);
        a = js.transpose() * js;
    };
    // The held columns with an effect (unobservable: in the span of the fitted ones), unit-scaled: what
    // the fit makes the fitted parameters carry of them is reported with the estimates.
    std::vector<std::size_t> held;
    for (std::size_t c = 0; c < out.estimates.size(); ++c)
        if (std::find(cols.begin(), cols.end(), static_cast<int>(c)) == cols.end() &&
            out.estimates[c].sensitivity > opt.min_sensitivity)
            held.push_back(c);
    set_jacobian(select(jac_full));
    jac_full = Eigen::MatrixXd();
    out.jacobian_evaluations = 1;
    bool jac_current = true;  // evaluated at the current estimate
    double lambda = 1e-6;
    out.message = "iteration limit reached";
    auto refresh = [&] {
        js = Eigen::MatrixXd();  // freed before the new one is evaluated
        set_jacobian(select(jacobian(readings, prep, e, opt.free_params, offsets, opt.fit_socket_offsets)));
        jac_current = true;
        ++out.jacobian_evaluations;
    };
    for (out.iterations = 1; out.iterations <= opt.max_iterations && m > 0; ++out.iterations) {
        const Eigen::VectorXd g = js.transpose() * r;
        // A step changing the predictions by less than this is statistically nothing.
        const double negligible =
            opt.step_tolerance * std::sqrt(cost / static_cast<double>(out.readings - static_cast<std::size_t>(m))) +
            1e-13;
        bool accepted = false;
        bool stale_failure = false;
        bool negligible_failure = false;
        double step_norm = 0;
        double new_cost = cost;
        double rho = 1;
        for (int tries = 0; tries < 12 && !accepted && !stale_failure; ++tries) {
            Eigen::MatrixXd damped = a;
            damped.diagonal().array() *= 1.0 + lambda;
            const Eigen::VectorXd ds = damped.ldlt().solve(g);
            const Eigen::VectorXd delta = ds.cwiseQuotient(scale);
            ErrorParams e_try = e;
            std::vector<Vec3> off_try = offsets;
            apply_step(delta, e_try, off_try);
            const Eigen::VectorXd r_try = measured_minus_predicted(e_try, off_try);
            new_cost = r_try.squaredNorm();
            if (std::isfinite(new_cost) && new_cost <= cost) {
                const double predicted = cost - (r - js * ds).squaredNorm();
                // Steps too small to matter against the residual say nothing about linearity.
                rho = predicted > 1e-6 * cost ? (cost - new_cost) / predicted : 1.0;
                accepted = true;
                e = e_try;
                offsets = off_try;
                r = r_try;
                step_norm = ds.norm();
                lambda = std::max(lambda * 0.1, 1e-12);
            } else if (ds.norm() <= negligible) {
                negligible_failure = true;  // at the minimum to a fraction of the uncertainties
                break;
            } else if (!jac_current) {
                stale_failure = true;  // first try a fresh Jacobian, then more damping
            } else {
                lambda *= 10.0;
            }
        }
        if (stale_failure) {
            refresh();
            continue;
        }
        if (negligible_failure) {
            out.converged = true;
            out.message = "step below tolerance";
            break;
        }
        if (!accepted) {
            // No decrease possible: at the minimum to working precision.
            out.converged = true;
            out.message = "no further decrease of the residual";
            break;
        }
        jac_current = false;
        const double old_cost = cost;
        cost = new_cost;
        // Converged when the step moved the predictions by a small fraction of the reading noise (in
        // scaled units a step of one σ_reading is about one standard uncertainty or less).
        if (step_norm <= negligible || old_cost - cost <= 1e-14 * old_cost) {
            out.converged = true;
            out.message = "step below tolerance";
            if (std::abs(1.0 - rho) > 1e-3) refresh();  // uncertainties need the Jacobian at the solution
            break;
        }
        if (std::abs(1.0 - rho) > 1e-3) refresh();
    }
    if (m == 0) {
        out.converged = true;
        out.message = "nothing observable to fit";
        out.iterations = 0;
    }
    out.iterations = std::min(out.iterations, opt.max_iterations);

    // Uncertainties from the residual variance and the (scaled) normal matrix at the solution.
    out.degrees_of_freedom = out.readings - static_cast<std::size_t>(m);
    out.residual_rms_mm = std::sqrt(cost / static_cast<double>(out.readings));
    out.residual_sigma_mm = std::sqrt(cost / static_cast<double>(out.degrees_of_freedom));
    {
        double sum = 0;
        std::size_t given = 0;
        for (const Reading& rd : readings.readings) {
            if (rd.std_mm && rd.n > 0 && std::isfinite(*rd.std_mm)) {
                sum += *rd.std_mm * *rd.std_mm / rd.n;
                ++given;
            }
        }
        const double stated = given > 0 ? std::sqrt(sum / static_cast<double>(given)) : 0.0;
        out.noise_floor_mm = std::max(stated, opt.min_reading_sigma_mm);
    }
    out.uncertainty_from_floor = out.residual_sigma_mm < out.noise_floor_mm;
    const double sigma2 = out.uncertainty_from_floor ? out.noise_floor_mm * out.noise_floor_mm
                                                     : out.residual_sigma_mm * out.residual_sigma_mm;
    out.correlation = Eigen::MatrixXd::Identity(m, m);
    if (m > 0) {
        const Eigen::MatrixXd ainv = a.ldlt().solve(Eigen::MatrixXd::Identity(m, m));
        for (Eigen::Index j = 0; j < m; ++j) {
            auto& pe = out.estimates[static_cast<std::size_t>(cols[static_cast<std::size_t>(j)])];
            pe.observable = true;
            pe.std = std::sqrt(sigma2 * ainv(j, j)) / scale[j];
            pe.independence = 1.0 / std::sqrt(ainv(j, j));
            for (Eigen::Index k = 0; k < m; ++k)
                out.correlation(j, k) = ainv(j, k) / std::sqrt(ainv(j, j) * ainv(k, k));
        }
        if (!held.empty()) {
            // The held columns at the solution, unit-scaled. At most two n × m matrices live at once
            // (docs/identification.md, memory): js is done with.
            js = Eigen::MatrixXd();
            Eigen::MatrixXd at_solution = jacobian(readings, prep, e, opt.free_params, offsets, opt.fit_socket_offsets);
            Eigen::MatrixXd jh(at_solution.rows(), static_cast<Eigen::Index>(held.size()));
            Eigen::VectorXd held_norm(static_cast<Eigen::Index>(held.size()));
            for (std::size_t k = 0; k < held.size(); ++k) {
                const auto col = at_solution.col(static_cast<Eigen::Index>(held[k]));
                held_norm[static_cast<Eigen::Index>(k)] = col.norm();
                jh.col(static_cast<Eigen::Index>(k)) = col / col.norm();
            }
            // A held unit direction h ≈ Σ f_j q_j over the fitted unit columns f at the solution:
            // q = (fᵀf)⁻¹ fᵀ h, dimensionless. The estimate of fitted j then moves by q_j · |J_h| / |J_j|
            // (its unit) per unit of the held parameter.
            Eigen::MatrixXd f = select(at_solution);
            at_solution = Eigen::MatrixXd();
            const Eigen::VectorXd norm = f.colwise().norm().transpose();
            for (Eigen::Index k = 0; k < m; ++k)
                if (norm[k] > 0) f.col(k) /= norm[k];
            const Eigen::MatrixXd q = (f.transpose() * f).ldlt().solve(f.transpose() * jh);
            for (Eigen::Index j = 0; j < m; ++j) {
                auto& pe = out.estimates[static_cast<std::size_t>(cols[static_cast<std::size_t>(j)])];
                for (Eigen::Index k = 0; k < q.cols(); ++k)
                    if (std::abs(q(j, k)) >= 1e-3 && norm[j] > 0)
                        pe.carries.push_back({out.estimates[held[static_cast<std::size_t>(k)]].name,
                                              q(j, k) * held_norm[k] / norm[j], q(j, k)});
            }
        }
    }
    for (auto& pe : out.estimates) {
        if (pe.param)
            pe.estimate = pe.observable ? e[*pe.param] : opt.fixed[*pe.param];
        else
            pe.estimate = offsets[static_cast<std::size_t>(pe.socket)][pe.axis];
    }
    out.model = e;
    for (std::size_t k = 0; k < out.sockets.size(); ++k) out.sockets[k].offset_mm = offsets[k];
    return out;
}

}  // namespace ballbar::analysis
