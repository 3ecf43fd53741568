// SPDX-License-Identifier: MIT
// The discovery loop: base fit → linearised score test of every candidate → refit of the winner.
// Then the residual analysis (directional trends against the explaining variables) and the F
// distribution's tail.
#include "ballbar/analysis/discovery.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "ballbar/analysis/kinematics.hpp"
#include "discovery_search.hpp"

namespace ballbar::analysis {
namespace {

/// Pseudo-inverse of a symmetric positive semi-definite matrix with unit diagonal (a correlation-like
/// Gram matrix of unit columns): eigenvalues below `tol` are treated as zero.
Eigen::MatrixXd pinv_psd(const Eigen::MatrixXd& g, double tol = 1e-12) {
    if (g.rows() == 0) return g;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(g);
    Eigen::VectorXd inv = es.eigenvalues();
    for (Eigen::Index i = 0; i < inv.size(); ++i) inv[i] = inv[i] > tol ? 1.0 / inv[i] : 0.0;
    return es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
}

/// Names of the columns of the discovery Jacobian: the parameters, then socket<k>.x/y/z.
std::string column_name(std::span<const Param> params, Eigen::Index col) {
    const auto p = static_cast<std::size_t>(col);
    if (p < params.size()) return std::string(param_info(params[p]).name);
    const std::size_t s = p - params.size();
    return "socket" + std::to_string(s / 3) + "." + "xyz"[s % 3];
}

/// Adds a group unless it is already reported (or contained in a reported one).
void add_group(std::vector<std::vector<std::string>>& groups, std::vector<std::string> group) {
    for (const auto& g : groups)
        if (std::all_of(group.begin(), group.end(),
                        [&g](const std::string& name) { return std::find(g.begin(), g.end(), name) != g.end(); }))
            return;
    groups.push_back(std::move(group));
}

/// The linear algebra of one step, on the Gram matrix of the unit-scaled Jacobian columns.
struct Projection {
    std::vector<Eigen::Index> model;  ///< columns in the current model
    Eigen::MatrixXd gmm_pinv;         ///< (G_MM)^+

    Projection(const Eigen::MatrixXd& gram, std::vector<Eigen::Index> cols) : model(std::move(cols)) {
        Eigen::MatrixXd gmm(model.size(), model.size());
        for (std::size_t i = 0; i < model.size(); ++i)
            for (std::size_t j = 0; j < model.size(); ++j) gmm(i, j) = gram(model[i], model[j]);
        gmm_pinv = pinv_psd(gmm);
    }
    Eigen::VectorXd cross(const Eigen::MatrixXd& gram, Eigen::Index c) const {
        Eigen::VectorXd v(model.size());
        for (std::size_t i = 0; i < model.size(); ++i) v[i] = gram(model[i], c);
        return v;
    }
    Eigen::VectorXd model_part(const Eigen::VectorXd& g) const {
        Eigen::VectorXd v(model.size());
        for (std::size_t i = 0; i < model.size(); ++i) v[i] = g[model[i]];
        return v;
    }
    /// Inner product of columns a and b after the model's columns are projected out.
    double inner(const Eigen::MatrixXd& gram, Eigen::Index a, Eigen::Index b) const {
        return gram(a, b) - cross(gram, a).dot(gmm_pinv * cross(gram, b));
    }
};

struct StepContext {
    const ReadingSet& readings;
    const DiscoveryOptions& options;
    std::vector<Param> columns;  ///< the Jacobian's parameter columns (model and candidates)
    Eigen::MatrixXd jac;         ///< unit-scaled columns
    Eigen::MatrixXd gram;
    Eigen::MatrixXd variables;
};

Eigen::Index column_of(const StepContext& ctx, Param p) {
    const auto it = std::find(ctx.columns.begin(), ctx.columns.end(), p);
    return static_cast<Eigen::Index>(it - ctx.columns.begin());
}

std::vector<Eigen::Index> model_columns(const StepContext& ctx, const FitSummary& fit) {
    std::vector<Eigen::Index> out;
    for (std::size_t idx : fit.fitted) {
        const ParamEstimate& e = fit.estimates[idx];
        if (e.param)
            out.push_back(column_of(ctx, *e.param));
        else
            out.push_back(static_cast<Eigen::Index>(ctx.columns.size()) + 3 * e.socket + e.axis);
    }
    return out;
}

Eigen::VectorXd residuals_of(const ReadingSet& readings, const FitSummary& fit) {
    std::vector<Vec3> offsets;
    for (const auto& s : fit.sockets) offsets.push_back(s.offset_mm);
    return reading_residuals(readings, fit.model, offsets);
}

FitSummary fit_model(const ReadingSet& readings, const std::vector<Param>& model, const ErrorParams& start) {
    FitOptions fo;
    fo.free_params = model;
    fo.fixed = start;
    return fit_error_model(readings, fo);
}

double explained_r2(const Eigen::VectorXd& r, const Eigen::MatrixXd& vars, ExplainingVariable v);

/// The open candidates' linearised scores in one step, and what the subset search needs.
struct StepScores {
    std::vector<CandidateScore> scores;  ///< testable candidates
    std::vector<Eigen::Index> cols;      ///< their Jacobian columns
    Eigen::MatrixXd p;                   ///< Gram matrix of their columns with the model projected out
    Eigen::VectorXd t;                   ///< their projected scores against the residual
    double sigma2 = 0;                   ///< noise variance with every testable candidate added
    double dof = 0;                      ///< its degrees of freedom
};

/// Smallest eigenvalue of a Gram matrix scaled to unit diagonal.
double min_scaled_eigenvalue(const Eigen::MatrixXd& g) {
    const Eigen::VectorXd d = g.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
    const Eigen::MatrixXd q = d.asDiagonal() * g * d.asDiagonal();
    return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(q, Eigen::EigenvaluesOnly).eigenvalues()[0];
}

StepScores score_candidates(const StepContext& ctx, const Projection& proj, const Eigen::VectorXd& r,
                            std::vector<const Effect*>& open, DiscoveryResult& out) {
    StepScores sc;
    const Eigen::VectorXd g = ctx.jac.transpose() * r;
    const Eigen::VectorXd gm = proj.gmm_pinv * proj.model_part(g);
    const double rss = r.squaredNorm();
    const auto n = static_cast<double>(r.size());
    const auto pm = static_cast<double>(proj.model.size());
    std::vector<double> t;
    for (auto it = open.begin(); it != open.end();) {
        const Eigen::Index c = column_of(ctx, (*it)->param);
        const double pn = std::max(0.0, proj.inner(ctx.gram, c, c));
        CandidateScore s{*it, std::sqrt(pn / std::max(ctx.gram(c, c), 1e-300)), 0, 0, 1, false};
        if (ctx.gram(c, c) == 0 || s.independence < ctx.options.min_independence) {
            // The model absorbs it: unidentifiable, confounded with the model columns it is made of.
            out.unidentifiable.push_back(std::string((*it)->id));
            const Eigen::VectorXd beta = proj.gmm_pinv * proj.cross(ctx.gram, c);
            const double big = beta.size() ? beta.cwiseAbs().maxCoeff() : 0.0;
            std::vector<std::string> group{std::string((*it)->id)};
            for (std::size_t i = 0; i < proj.model.size(); ++i)
                if (big > 0 && std::abs(beta[static_cast<Eigen::Index>(i)]) >= 0.1 * big)
                    group.push_back(column_name(ctx.columns, proj.model[i]));
            if (group.size() > 1) add_group(out.confounded, group);
            it = open.erase(it);
            continue;
        }
        t.push_back(g[c] - proj.cross(ctx.gram, c).dot(gm));
        s.delta_rss_mm2 = std::min(t.back() * t.back() / pn, rss);
        sc.scores.push_back(s);
        sc.cols.push_back(c);
        ++it;
    }
    const auto m = static_cast<Eigen::Index>(sc.cols.size());
    sc.t = Eigen::Map<const Eigen::VectorXd>(t.data(), m);
    sc.p.resize(m, m);
    for (Eigen::Index i = 0; i < m; ++i)
        for (Eigen::Index j = 0; j < m; ++j) sc.p(i, j) = proj.inner(ctx.gram, sc.cols[i], sc.cols[j]);
    // Noise variance from the model with every testable candidate (pseudo-inverse: dependent
    // combinations count once).
    if (m > 0) {
        const Eigen::VectorXd d = sc.p.diagonal().cwiseSqrt().cwiseInverse();
        const Eigen::MatrixXd q = d.asDiagonal() * sc.p * d.asDiagonal();
        const double tol = ctx.options.min_independence * ctx.options.min_independence;
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(q);
        double reduction = 0;
        int rank = 0;
        const Eigen::VectorXd proj_t = es.eigenvectors().transpose() * (d.asDiagonal() * sc.t);
        for (Eigen::Index k = 0; k < m; ++k)
            if (es.eigenvalues()[k] > tol) {
                reduction += proj_t[k] * proj_t[k] / es.eigenvalues()[k];
                ++rank;
            }
        sc.dof = n - pm - rank;
        sc.sigma2 = sc.dof > 0 ? std::max(rss - reduction, 0.0) / sc.dof : 0.0;
    }
    for (auto& s : sc.scores) {
        s.f = sc.sigma2 > 0 ? s.delta_rss_mm2 / sc.sigma2 : 0.0;
        s.p_value = sc.dof > 0 ? f_distribution_sf(s.f, 1.0, sc.dof) : 1.0;
        s.passes = s.p_value < ctx.options.family_alpha / static_cast<double>(m);
    }
    return sc;
}

/// Groups of testable candidates the data cannot tell apart: near-null combinations of their
/// projected columns (an eigenvalue of the unit-scaled projected Gram matrix below 1 − confound_cos).
void report_confounded_groups(const StepScores& sc, const DiscoveryOptions& options, DiscoveryResult& out) {
    const Eigen::Index m = sc.p.rows();
    if (m < 2) return;
    const Eigen::VectorXd d = sc.p.diagonal().cwiseSqrt().cwiseInverse();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(d.asDiagonal() * sc.p * d.asDiagonal());
    for (Eigen::Index k = 0; k < m && es.eigenvalues()[k] < 1.0 - options.confound_cos; ++k) {
        const Eigen::VectorXd v = es.eigenvectors().col(k);
        const double big = v.cwiseAbs().maxCoeff();
        std::vector<std::pair<double, std::string>> members;
        for (Eigen::Index i = 0; i < m; ++i)
            if (std::abs(v[i]) >= 0.3 * big)
                members.emplace_back(-std::abs(v[i]), std::string(sc.scores[static_cast<std::size_t>(i)].effect->id));
        if (members.size() < 2) continue;
        std::sort(members.begin(), members.end());
        std::vector<std::string> group;
        for (auto& [w, id] : members) group.push_back(std::move(id));
        add_group(out.confounded, std::move(group));
    }
}

/// The sparsest explanation: the subset S of testable candidates (|S| ≤ max_subset, members not
/// confounded with each other) minimising −ΔRSS(S)/σ² + λ·|S|, λ the single-parameter F threshold.
/// Empty when no subset beats the model as it is.
std::vector<std::size_t> best_subset(const StepScores& sc, const DiscoveryOptions& options, double lambda,
                                     double* cost_out = nullptr) {
    const std::size_t m = sc.scores.size();
    const double tol = options.min_independence * options.min_independence;
    std::vector<std::size_t> best, cur;
    double best_cost = 0;
    auto visit = [&](auto&& self, std::size_t from) -> void {
        if (!cur.empty()) {
            const auto k = static_cast<Eigen::Index>(cur.size());
            Eigen::MatrixXd pss(k, k);
            Eigen::VectorXd ts(k);
            for (Eigen::Index i = 0; i < k; ++i) {
                ts[i] = sc.t[static_cast<Eigen::Index>(cur[static_cast<std::size_t>(i)])];
                for (Eigen::Index j = 0; j < k; ++j)
                    pss(i, j) = sc.p(static_cast<Eigen::Index>(cur[static_cast<std::size_t>(i)]),
                                     static_cast<Eigen::Index>(cur[static_cast<std::size_t>(j)]));
            }
            if (k > 1 && min_scaled_eigenvalue(pss) < tol) return;  // members confounded: not a subset to fit
            const double reduction = ts.dot(pss.ldlt().solve(ts));
            const double cost = -reduction / sc.sigma2 + lambda * static_cast<double>(k);
            if (cost < best_cost) {
                best_cost = cost;
                best = cur;
            }
        }
        if (cur.size() >= static_cast<std::size_t>(options.max_subset)) return;
        for (std::size_t i = from; i < m; ++i) {
            cur.push_back(i);
            self(self, i + 1);
            cur.pop_back();
        }
    };
    visit(visit, 0);
    if (cost_out) *cost_out = best_cost;
    return best;
}

/// The variable whose directional trend explains `r` best.
ExplainingVariable best_variable(const Eigen::VectorXd& r, const Eigen::MatrixXd& variables) {
    ExplainingVariable out = ExplainingVariable::bar_direction;
    double best = -1;
    for (std::size_t v = 0; v < kExplainingVariableCount; ++v) {
        const double r2 = explained_r2(r, variables, static_cast<ExplainingVariable>(v));
        if (r2 > best) {
            best = r2;
            out = static_cast<ExplainingVariable>(v);
        }
    }
    return out;
}

}  // namespace

namespace {

/// The readings in order of each explaining variable, ties in reading order (what a stable sort
/// gives), sorted on first use: the variables do not change during a discovery run, whose residual
/// analyses would otherwise sort every reading twenty times.
class VariableOrders {
  public:
    explicit VariableOrders(const Eigen::MatrixXd& variables) : variables_(&variables) {}
    const std::vector<Eigen::Index>& of(ExplainingVariable v);

  private:
    const Eigen::MatrixXd* variables_;
    std::array<std::vector<Eigen::Index>, kExplainingVariableCount> orders_;
};

VariableTrend trend_of(const Eigen::VectorXd& residual_mm, const Eigen::MatrixXd& variables, ExplainingVariable v,
                       VariableOrders& orders);
ResidualAnalysis analyse_with(const Eigen::VectorXd& residual_mm, const Eigen::MatrixXd& variables,
                              VariableOrders& orders);

/// The learned terms of the workflow: their values, raw and unit columns (appended to the context's
/// Jacobian), and the readings with their contribution taken off (what the library fit sees).
struct Learned {
    std::vector<LearnedTerm> terms;
    std::vector<Eigen::VectorXd> raw;
    std::vector<double> norm;
    std::vector<Eigen::Index> cols;  ///< their columns in ctx.jac
    ReadingSet corrected;
};

void append_columns(StepContext& ctx, const std::vector<Eigen::VectorXd>& raw, Learned& learned) {
    const Eigen::Index old = ctx.jac.cols();
    const auto k = static_cast<Eigen::Index>(raw.size());
    ctx.jac.conservativeResize(Eigen::NoChange, old + k);
    for (Eigen::Index j = 0; j < k; ++j) {
        const double norm = raw[static_cast<std::size_t>(j)].norm();
        ctx.jac.col(old + j) = raw[static_cast<std::size_t>(j)] / norm;
        learned.raw.push_back(raw[static_cast<std::size_t>(j)]);
        learned.norm.push_back(norm);
        learned.cols.push_back(old + j);
    }
    const Eigen::MatrixXd cross = ctx.jac.transpose() * ctx.jac.rightCols(k);
    Eigen::MatrixXd g(old + k, old + k);
    g.topLeftCorner(old, old) = ctx.gram;
    g.rightCols(k) = cross;
    g.bottomRows(k) = cross.transpose();
    ctx.gram = std::move(g);
}

/// The readings with the learned terms' contribution taken off.
void apply_terms(const ReadingSet& readings, Learned& learned) {
    learned.corrected = readings;
    for (std::size_t j = 0; j < learned.terms.size(); ++j)
        for (std::size_t i = 0; i < readings.readings.size(); ++i)
            learned.corrected.readings[i].measured_mm -=
                learned.terms[j].value * learned.raw[j][static_cast<Eigen::Index>(i)];
}

/// One Gauss–Newton step of the learned terms against the current fit (their part of the joint
/// least-squares step, the model's columns projected out); returns the change in σ units.
double rebalance(const StepContext& ctx, const FitSummary& fit, const Eigen::VectorXd& r, Learned& learned,
                 double* sigma2_out = nullptr) {
    if (learned.terms.empty()) return 0;
    const Projection proj(ctx.gram, model_columns(ctx, fit));
    const Eigen::VectorXd g = ctx.jac.transpose() * r;
    const Eigen::VectorXd gm = proj.gmm_pinv * proj.model_part(g);
    const auto k = static_cast<Eigen::Index>(learned.cols.size());
    Eigen::MatrixXd p(k, k);
    Eigen::VectorXd t(k);
    for (Eigen::Index i = 0; i < k; ++i) {
        const Eigen::Index ci = learned.cols[static_cast<std::size_t>(i)];
        t[i] = g[ci] - proj.cross(ctx.gram, ci).dot(gm);
        for (Eigen::Index j = 0; j < k; ++j)
            p(i, j) = proj.inner(ctx.gram, ci, learned.cols[static_cast<std::size_t>(j)]);
    }
    const Eigen::MatrixXd inv = p.ldlt().solve(Eigen::MatrixXd::Identity(k, k));
    const Eigen::VectorXd dc = inv * t;
    const double dof = static_cast<double>(r.size()) - static_cast<double>(proj.model.size()) - static_cast<double>(k);
    const double sigma2 = std::max(r.squaredNorm() - t.dot(dc), 1e-300) / std::max(dof, 1.0);
    if (sigma2_out) *sigma2_out = sigma2;
    for (Eigen::Index i = 0; i < k; ++i) {
        auto& l = learned.terms[static_cast<std::size_t>(i)];
        l.value += dc[i] / learned.norm[static_cast<std::size_t>(i)];
        l.std_error = std::sqrt(sigma2 * inv(i, i)) / learned.norm[static_cast<std::size_t>(i)];
    }
    return dc.norm() / std::sqrt(sigma2);
}

}  // namespace

DiscoveryResult discover(const ReadingSet& readings, const DiscoveryOptions& options) {
    const MachineType type = readings.machine.type;
    DiscoveryResult out;
    out.type = type;
    const auto n = static_cast<Eigen::Index>(readings.readings.size());

    // 1. The base model, with the parameters the data cannot determine left out.
    std::vector<Param> requested = options.base_model.empty() ? rotary_params_for(type) : options.base_model;
    FitSummary fit = fit_model(readings, requested, ErrorParams{});
    std::vector<Param> model;
    for (const ParamEstimate& e : fit.estimates) {
        if (!e.observable) {
            out.unidentifiable.push_back(e.name);
            continue;
        }
        if (e.param) model.push_back(*e.param);
    }
    // The fit already held the unobservable ones at their start values and fitted the rest: it is the
    // base model's fit.
    out.base_model = model;
    out.base_fit = fit.model;
    std::vector<Vec3> base_offsets;
    for (const auto& s : fit.sockets) base_offsets.push_back(s.offset_mm);

    // 2. One Jacobian over the model and every candidate, at the base fit; unit-scaled columns.
    StepContext ctx{readings, options, model, {}, {}, explaining_variables(readings)};
    std::vector<const Effect*> candidates = candidate_effects(type, requested);
    for (const Effect* c : candidates) ctx.columns.push_back(c->param);
    ctx.jac = reading_jacobian(readings, fit.model, ctx.columns, base_offsets, true);
    for (Eigen::Index j = 0; j < ctx.jac.cols(); ++j) {
        const double norm = ctx.jac.col(j).norm();
        if (norm > 0) ctx.jac.col(j) /= norm;
    }
    ctx.gram = ctx.jac.transpose() * ctx.jac;

    Eigen::VectorXd r = residuals_of(readings, fit);
    out.rms_initial_mm = fit.residual_rms_mm;
    VariableOrders orders(ctx.variables);
    out.initial_residuals = analyse_with(r, ctx.variables, orders);

    Learned learned;
    const ReadingSet* data = &readings;  // the readings the fits see (learned terms taken off)
    auto unknowns = [&] { return static_cast<double>(fit.fitted.size()) + static_cast<double>(learned.terms.size()); };
    auto all_model_columns = [&] {
        std::vector<Eigen::Index> cols = model_columns(ctx, fit);
        cols.insert(cols.end(), learned.cols.begin(), learned.cols.end());
        return cols;
    };
    // Refit with the learned terms held, then one joint step of the terms and a last refit.
    auto refit_with_terms = [&](const std::vector<Param>& params, const ErrorParams& start) {
        FitSummary f = fit_model(*data, params, start);
        if (learned.terms.empty()) return f;
        std::swap(fit, f);
        const double moved = rebalance(ctx, fit, residuals_of(*data, fit), learned);
        std::swap(fit, f);
        if (moved > 0.05) {  // the terms moved by more than 5 % of their uncertainty: refit the rest
            apply_terms(readings, learned);
            f = fit_model(*data, params, f.model);
        }
        return f;
    };

    // The noise floor (repeated points: from the base fit's residuals) and the search beyond the library.
    out.noise_floor = estimate_noise_floor(readings, r, options.noise_mm, options.resolution_mm);
    const std::vector<EmpiricalFamily> families = empirical_families(readings);
    std::optional<TermBasis> basis;
    auto search_now = [&] {
        if (!basis) basis = term_basis(readings, out.base_fit, base_offsets);
        const std::vector<Eigen::Index> mcols = all_model_columns();
        Eigen::MatrixXd mjac(n, static_cast<Eigen::Index>(mcols.size()));
        Eigen::MatrixXd mgram(mjac.cols(), mjac.cols());
        for (std::size_t i = 0; i < mcols.size(); ++i) {
            mjac.col(static_cast<Eigen::Index>(i)) = ctx.jac.col(mcols[i]);
            for (std::size_t j = 0; j < mcols.size(); ++j)
                mgram(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = ctx.gram(mcols[i], mcols[j]);
        }
        const double alpha_s = out.noise_floor.known() ? options.search_alpha : options.search_alpha_unknown_floor;
        detail::SearchInput in{
            readings, mjac, mgram, r, *basis, families, learned.terms, alpha_s, options.min_independence};
        return detail::search_beyond_library(in);
    };
    std::optional<detail::SearchOutput> pending;  // a search that beat the library's best step

    std::vector<const Effect*> open = candidates;  // still to test
    double alpha = options.family_alpha;
    auto library_steps = [&] {
        for (int step = static_cast<int>(out.steps.size()); step < options.max_steps && !open.empty(); ++step) {
            std::vector<Eigen::Index> mcols = all_model_columns();
            const Projection proj(ctx.gram, mcols);
            const double rss = r.squaredNorm();
            // Below the instrument's resolution nothing is structure: no effect is added to explain it.
            if (out.noise_floor.raised_to_resolution &&
                std::sqrt(rss / static_cast<double>(n)) < out.noise_floor.sigma_mm)
                break;
            StepScores sc = score_candidates(ctx, proj, r, open, out);
            if (sc.scores.empty() || sc.sigma2 <= 0) break;
            alpha = options.family_alpha / static_cast<double>(sc.scores.size());
            report_confounded_groups(sc, options, out);
            double cost = 0;
            const std::vector<std::size_t> chosen = best_subset(sc, options, f_critical(alpha, 1.0, sc.dof), &cost);
            if (chosen.empty()) break;
            // With a known floor and structure above it, a family beyond the library may explain more:
            // the larger of the two scores (ΔRSS/σ² − thresholds) goes first.
            // (No search when the library's explanation already takes 90 % of the excess over the floor:
            // no family could beat it.)
            const double lambda = f_critical(alpha, 1.0, sc.dof);
            const double explained = (lambda * static_cast<double>(chosen.size()) - cost) * sc.sigma2;
            const double excess =
                rss - (static_cast<double>(n) - unknowns()) * out.noise_floor.sigma_mm * out.noise_floor.sigma_mm;
            if (out.noise_floor.known() && static_cast<int>(out.learned.size()) < options.max_learned &&
                explained < 0.9 * excess &&
                noise_verdict(r, unknowns(), out.noise_floor, options.noise_alpha).structure) {
                // Both scored against the floor; the library is preferred unless the family explains
                // clearly more (its score 20 % above the library's).
                detail::SearchOutput found = search_now();
                const double s2 = out.noise_floor.sigma_mm * out.noise_floor.sigma_mm;
                const double lib_score = explained / s2 - lambda * static_cast<double>(chosen.size());
                if (found.found && found.delta_rss_mm2 / s2 - found.penalty > 1.2 * lib_score) {
                    pending = std::move(found);
                    break;
                }
            }
            // The most visible member of the best explanation goes first.
            std::size_t first = chosen.front();
            for (std::size_t i : chosen)
                if (sc.scores[i].f > sc.scores[first].f) first = i;
            const Effect* winner = sc.scores[first].effect;
            open.erase(std::find(open.begin(), open.end(), winner));

            // Refit with the winner.
            std::vector<Param> extended = model;
            extended.push_back(winner->param);
            FitSummary refit = refit_with_terms(extended, fit.model);
            const ParamEstimate* est = refit.find(param_info(winner->param).name);
            if (!est || !est->observable) {
                out.unidentifiable.push_back(std::string(winner->id));
                continue;
            }
            const Eigen::VectorXd r_new = residuals_of(*data, refit);
            const double rss_new = r_new.squaredNorm();
            const double dof_new =
                static_cast<double>(refit.degrees_of_freedom) - static_cast<double>(learned.terms.size());
            DiscoveryStep st;
            st.effect = winner;
            st.estimate = st.estimate_when_added = est->estimate;
            st.std_error = est->std;
            st.rms_before_mm = std::sqrt(rss / static_cast<double>(n));
            st.rms_after_mm = std::sqrt(rss_new / static_cast<double>(n));
            st.criterion = "F";
            st.value = (rss - rss_new) / std::max(rss_new / std::max(dof_new, 1.0), 1e-300);
            st.p_value = f_distribution_sf(st.value, 1.0, std::max(dof_new, 1.0));
            st.explained_by = best_variable(r - r_new, ctx.variables);
            st.trend_before = trend_of(r, ctx.variables, st.explained_by, orders);
            st.trend_after = trend_of(r_new, ctx.variables, st.explained_by, orders);
            st.model_after = refit.model;
            st.candidates = sc.scores;
            std::sort(st.candidates.begin(), st.candidates.end(),
                      [](const auto& a, const auto& b) { return a.f > b.f; });
            out.steps.push_back(std::move(st));
            model = std::move(extended);
            fit = std::move(refit);
            r = r_new;
        }
    };
    library_steps();
    // A library effect added while unexplained structure inflated the residual may owe its place to
    // that structure: once a term explains it, each is tested again given the rest of the model.
    auto withdraw_insignificant = [&] {
        for (;;) {
            DiscoveryStep* weakest = nullptr;
            double weakest_f = 0;
            int active = 0;
            for (DiscoveryStep& st : out.steps) {
                if (st.withdrawn) continue;
                ++active;
                const ParamEstimate* e = fit.find(param_info(st.effect->param).name);
                if (!e || !e->observable || !(e->std > 0)) continue;
                const double f = (e->estimate / e->std) * (e->estimate / e->std);
                if (!weakest || f < weakest_f) {
                    weakest = &st;
                    weakest_f = f;
                }
            }
            if (!weakest) return;
            const double dof =
                std::max(static_cast<double>(fit.degrees_of_freedom) - static_cast<double>(learned.terms.size()), 1.0);
            if (f_distribution_sf(weakest_f, 1.0, dof) <= options.family_alpha / active) return;
            weakest->withdrawn = true;
            model.erase(std::find(model.begin(), model.end(), weakest->effect->param));
            ErrorParams start = fit.model;
            start[weakest->effect->param] = 0;
            fit = refit_with_terms(model, start);
            r = residuals_of(*data, fit);
        }
    };

    // 3. The verdict; beyond the library while the residual is structure.
    out.verdict_library = noise_verdict(r, unknowns(), out.noise_floor, options.noise_alpha);
    out.verdict = out.verdict_library;
    for (int round = 0; round < options.max_learned; ++round) {
        if (out.noise_floor.known() && !out.verdict.structure && !pending) break;
        detail::SearchOutput found = pending ? std::move(*pending) : search_now();
        pending.reset();
        for (const std::string& s : found.not_searchable)
            if (std::find(out.not_searchable.begin(), out.not_searchable.end(), s) == out.not_searchable.end())
                out.not_searchable.push_back(s);
        if (!found.found) {
            if (out.verdict.structure)
                out.unlocated =
                    "the residual is above the noise floor, and no family of the search (each rotary angle, each "
                    "linear axis, time, temperatures, bar direction) explains it at the criterion";
            break;
        }
        EmpiricalStep st = std::move(found.step);
        st.rms_before_mm = std::sqrt(r.squaredNorm() / static_cast<double>(n));
        for (const LearnedTerm& t : st.terms) learned.terms.push_back(t);
        append_columns(ctx, found.columns, learned);
        apply_terms(readings, learned);
        data = &learned.corrected;
        FitSummary refit = refit_with_terms(model, fit.model);
        const Eigen::VectorXd r_new = residuals_of(*data, refit);
        st.rms_after_mm = std::sqrt(r_new.squaredNorm() / static_cast<double>(n));
        // The main term (largest contribution) gives the trend's quantity.
        std::size_t main = 0;
        for (std::size_t k = 0; k < st.terms.size(); ++k)
            if (std::abs(st.terms[k].value) * found.columns[k].norm() >
                std::abs(st.terms[main].value) * found.columns[main].norm())
                main = k;
        st.trend_before = detail::term_trend(readings, *basis, st.terms[main].term, r, &st.trend_unit, &st.trend_label);
        st.trend_after =
            detail::term_trend(readings, *basis, st.terms[main].term, r_new, &st.trend_unit, &st.trend_label);
        st.trend_before.variable = st.trend_after.variable = ExplainingVariable::bar_direction;
        fit = std::move(refit);
        r = r_new;
        out.learned.push_back(std::move(st));
        library_steps();
        withdraw_insignificant();
        out.verdict = noise_verdict(r, unknowns(), out.noise_floor, options.noise_alpha);
    }
    // The learned terms' final values and uncertainties (joint with the final model).
    if (!learned.terms.empty()) {
        if (rebalance(ctx, fit, r, learned) > 0.05) {
            apply_terms(readings, learned);
            fit = fit_model(*data, model, fit.model);
            r = residuals_of(*data, fit);
            rebalance(ctx, fit, r, learned);  // uncertainties at the solution; the step is below tolerance
        }
        out.verdict = noise_verdict(r, unknowns(), out.noise_floor, options.noise_alpha);
        std::size_t k = 0;
        for (EmpiricalStep& st : out.learned) {
            for (LearnedTerm& t : st.terms) t = learned.terms[k++];
            st.description = detail::describe(st.family, st.terms);
        }
        out.learned_terms = learned.terms;
    }

    // Steps report the final model's estimates (an effect added early is re-estimated as later ones
    // join it).
    for (DiscoveryStep& st : out.steps)
        if (const ParamEstimate* e = fit.find(param_info(st.effect->param).name); !st.withdrawn && e && e->observable) {
            st.estimate = e->estimate;
            st.std_error = e->std;
        }
    out.final_model = model;
    out.rms_final_mm = std::sqrt(r.squaredNorm() / static_cast<double>(n));
    out.final_residuals = analyse_with(r, ctx.variables, orders);
    char text[300];
    std::snprintf(text, sizeof text,
                  "F-test per added parameter at a family-wise false-alarm rate of %g per step (Bonferroni), "
                  "sparsest explanation of up to %d effects; noise verdict chi-square against the noise floor at "
                  "p < %g; beyond the library nested F-tests at %g (Bonferroni over the groups of terms)",
                  options.family_alpha, options.max_subset, options.noise_alpha,
                  out.noise_floor.known() ? options.search_alpha : options.search_alpha_unknown_floor);
    out.criterion_text = text;
    out.final_fit = std::move(fit);
    out.variables = std::move(ctx.variables);
    return out;
}

// ---- Residual analysis ----------------------------------------------------------------------------

Eigen::MatrixXd explaining_variables(const ReadingSet& readings) {
    const auto n = static_cast<Eigen::Index>(readings.readings.size());
    Eigen::MatrixXd v(n, 10);
    const bool second_is_c = rotary_axes(readings.machine.type).second == 'C';
    for (Eigen::Index i = 0; i < n; ++i) {
        const Reading& r = readings.readings[static_cast<std::size_t>(i)];
        const BallCentres c = nominal_balls(readings.machine, r.pose, r.socket_mm);
        Vec3 u = c.tool - c.table;
        const double len = u.norm();
        if (len > 0) u /= len;
        v.row(i) << r.time_s, r.bar_temp_C.value_or(20.0), r.pose.X_mm, r.pose.Y_mm, r.pose.Z_mm, r.pose.A_rad,
            second_is_c ? r.pose.C_rad : r.pose.B_rad, u.x(), u.y(), u.z();
    }
    return v;
}

namespace {

/// R² (uncentred: fraction of Σr²) of r against the variable's directional trend.
double explained_r2(const Eigen::VectorXd& r, const Eigen::MatrixXd& vars, ExplainingVariable v) {
    const double total = r.squaredNorm();
    if (total <= 0 || r.size() == 0) return 0;
    const auto col = static_cast<Eigen::Index>(v);
    Eigen::Matrix4d ata = Eigen::Matrix4d::Zero();
    Eigen::Vector4d atr = Eigen::Vector4d::Zero();
    for (Eigen::Index i = 0; i < r.size(); ++i) {
        double s = 1.0;
        if (v != ExplainingVariable::bar_direction) s = vars(i, col) - (v == ExplainingVariable::bar_temp ? 20.0 : 0.0);
        const Eigen::Vector4d a(s, s * vars(i, 7), s * vars(i, 8), s * vars(i, 9));
        ata.noalias() += a * a.transpose();
        atr.noalias() += a * r[i];
    }
    // Scale to unit diagonal, then a pseudo-inverse: constant or missing variables explain nothing.
    Eigen::Vector4d d;
    for (int k = 0; k < 4; ++k) d[k] = ata(k, k) > 0 ? 1.0 / std::sqrt(ata(k, k)) : 0.0;
    const Eigen::Matrix4d scaled = d.asDiagonal() * ata * d.asDiagonal();
    const Eigen::Vector4d b = d.asDiagonal() * atr;
    const Eigen::MatrixXd inv = pinv_psd(scaled, 1e-10);
    return std::clamp(b.dot(inv * b) / total, 0.0, 1.0);
}

const std::vector<Eigen::Index>& VariableOrders::of(ExplainingVariable v) {
    std::vector<Eigen::Index>& order = orders_[static_cast<std::size_t>(v)];
    const Eigen::Index n = variables_->rows();
    if (static_cast<Eigen::Index>(order.size()) == n) return order;
    // Sorting (value, index) pairs gives the stable order without indirect comparisons.
    const auto col = static_cast<Eigen::Index>(v);
    std::vector<std::pair<double, Eigen::Index>> pairs(static_cast<std::size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) pairs[static_cast<std::size_t>(i)] = {(*variables_)(i, col), i};
    std::sort(pairs.begin(), pairs.end());
    order.resize(pairs.size());
    for (std::size_t i = 0; i < pairs.size(); ++i) order[i] = pairs[i].second;
    return order;
}

VariableTrend trend_of(const Eigen::VectorXd& residual_mm, const Eigen::MatrixXd& variables, ExplainingVariable v,
                       VariableOrders& orders) {
    if (variables.rows() != residual_mm.size())
        throw AnalysisError("residual analysis: one row of variables per residual is needed");
    VariableTrend t;
    t.variable = v;
    t.r2 = explained_r2(residual_mm, variables, v);
    const Eigen::Index n = residual_mm.size();
    if (v == ExplainingVariable::bar_direction || n == 0) return t;
    const auto col = static_cast<Eigen::Index>(v);
    const std::vector<Eigen::Index>& order = orders.of(v);
    constexpr int kBins = 8;
    for (int b = 0; b < kBins; ++b) {
        const std::size_t lo = order.size() * static_cast<std::size_t>(b) / kBins;
        const std::size_t hi = order.size() * static_cast<std::size_t>(b + 1) / kBins;
        if (hi <= lo) continue;
        double sv = 0, sr = 0;
        for (std::size_t i = lo; i < hi; ++i) {
            sv += variables(order[i], col);
            sr += residual_mm[order[i]];
        }
        const auto cnt = static_cast<double>(hi - lo);
        t.bin_centre.push_back(sv / cnt);
        t.bin_mean_mm.push_back(sr / cnt);
        t.bin_count.push_back(cnt);
    }
    return t;
}

ResidualAnalysis analyse_with(const Eigen::VectorXd& residual_mm, const Eigen::MatrixXd& variables,
                              VariableOrders& orders) {
    if (variables.rows() != residual_mm.size())
        throw AnalysisError("residual analysis: one row of variables per residual is needed");
    ResidualAnalysis out;
    out.residual_mm = residual_mm;
    const Eigen::Index n = residual_mm.size();
    out.rms_mm = n > 0 ? std::sqrt(residual_mm.squaredNorm() / static_cast<double>(n)) : 0.0;
    double best = -1;
    for (std::size_t k = 0; k < kExplainingVariableCount; ++k) {
        out.trends[k] = trend_of(residual_mm, variables, static_cast<ExplainingVariable>(k), orders);
        if (out.trends[k].r2 > best) {
            best = out.trends[k].r2;
            out.best = out.trends[k].variable;
        }
    }
    return out;
}

}  // namespace

VariableTrend residual_trend(const Eigen::VectorXd& residual_mm, const Eigen::MatrixXd& variables,
                             ExplainingVariable v) {
    VariableOrders orders(variables);
    return trend_of(residual_mm, variables, v, orders);
}

ResidualAnalysis analyse_residuals(const Eigen::VectorXd& residual_mm, const Eigen::MatrixXd& variables) {
    VariableOrders orders(variables);
    return analyse_with(residual_mm, variables, orders);
}

// ---- F distribution -------------------------------------------------------------------------------

namespace {

/// Continued fraction of the incomplete beta function (modified Lentz), valid for x < (a+1)/(a+b+2).
double beta_continued_fraction(double a, double b, double x) {
    constexpr double kTiny = 1e-300;
    constexpr double kEps = 1e-15;
    const double qab = a + b, qap = a + 1.0, qam = a - 1.0;
    double c = 1.0;
    double d = 1.0 - qab * x / qap;
    if (std::abs(d) < kTiny) d = kTiny;
    d = 1.0 / d;
    double h = d;
    for (int m = 1; m <= 10000; ++m) {
        const double m2 = 2.0 * m;
        double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if (std::abs(d) < kTiny) d = kTiny;
        c = 1.0 + aa / c;
        if (std::abs(c) < kTiny) c = kTiny;
        d = 1.0 / d;
        h *= d * c;
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if (std::abs(d) < kTiny) d = kTiny;
        c = 1.0 + aa / c;
        if (std::abs(c) < kTiny) c = kTiny;
        d = 1.0 / d;
        const double del = d * c;
        h *= del;
        if (std::abs(del - 1.0) < kEps) return h;
    }
    return h;
}

}  // namespace

double incomplete_beta(double a, double b, double x) {
    if (!(a > 0) || !(b > 0) || std::isnan(x)) throw AnalysisError("incomplete beta: a, b > 0 and x in [0, 1]");
    if (x <= 0) return 0.0;
    if (x >= 1) return 1.0;
    const double log_front =
        std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x);
    const double front = std::exp(log_front);
    if (x < (a + 1.0) / (a + b + 2.0)) return front * beta_continued_fraction(a, b, x) / a;
    return 1.0 - front * beta_continued_fraction(b, a, 1.0 - x) / b;
}

double f_distribution_sf(double f, double d1, double d2) {
    if (!(d1 > 0) || !(d2 > 0)) throw AnalysisError("F distribution: degrees of freedom must be positive");
    if (std::isnan(f)) return 1.0;
    if (f <= 0) return 1.0;
    if (std::isinf(f)) return 0.0;
    // P(F > f) = I_{d2/(d2 + d1 f)}(d2/2, d1/2).
    return incomplete_beta(d2 / 2.0, d1 / 2.0, d2 / (d2 + d1 * f));
}

}  // namespace ballbar::analysis
