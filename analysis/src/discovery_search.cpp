// SPDX-License-Identifier: MIT
// The search beyond the library: every family of empirical terms (the shapes of one variable) is
// scored by the score test around the current fit (its columns with the model projected out), its
// groups of terms chosen by forward selection with nested-model F-tests at a Bonferroni threshold over
// every group of the search, and the family that explains most beyond its thresholds wins.
#include "discovery_search.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "ballbar/analysis/kinematics.hpp"

namespace ballbar::analysis::detail {
namespace {

Eigen::MatrixXd pinv_psd_relative(const Eigen::MatrixXd& g, double tol = 1e-12) {
    if (g.rows() == 0) return g;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(g);
    Eigen::VectorXd inv = es.eigenvalues();
    const double top = std::max(inv.maxCoeff(), 1e-300);
    for (Eigen::Index i = 0; i < inv.size(); ++i) inv[i] = inv[i] > tol * top ? 1.0 / inv[i] : 0.0;
    return es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
}

Eigen::MatrixXd sub(const Eigen::MatrixXd& m, const std::vector<Eigen::Index>& idx) {
    const auto k = static_cast<Eigen::Index>(idx.size());
    Eigen::MatrixXd out(k, k);
    for (Eigen::Index i = 0; i < k; ++i)
        for (Eigen::Index j = 0; j < k; ++j)
            out(i, j) = m(idx[static_cast<std::size_t>(i)], idx[static_cast<std::size_t>(j)]);
    return out;
}

Eigen::VectorXd sub(const Eigen::VectorXd& v, const std::vector<Eigen::Index>& idx) {
    Eigen::VectorXd out(static_cast<Eigen::Index>(idx.size()));
    for (std::size_t i = 0; i < idx.size(); ++i) out[static_cast<Eigen::Index>(i)] = v[idx[i]];
    return out;
}

double min_scaled_eigen(const Eigen::MatrixXd& g) {
    const Eigen::VectorXd d = g.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
    const Eigen::MatrixXd q = d.asDiagonal() * g * d.asDiagonal();
    return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(q, Eigen::EigenvaluesOnly).eigenvalues()[0];
}

std::string number_format(const char* f, double v) {
    char buf[64];
    if (f[2] == '0')
        std::snprintf(buf, sizeof buf, "%.0f", v);
    else
        std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
}

const char* per_revolution(int k) {
    static const char* const names[] = {"", "once", "twice", "three times", "four times"};
    return k >= 1 && k <= 4 ? names[k] : "several times";
}

}  // namespace

SearchOutput search_beyond_library(const SearchInput& in) {
    SearchOutput out;
    const Eigen::Index n = in.residual_mm.size();
    struct Col {
        std::size_t family;
        EmpiricalTerm term;
        Eigen::VectorXd raw;
        double norm = 0;
    };
    std::vector<Col> cols;
    std::vector<std::vector<std::vector<Eigen::Index>>> groups(in.families.size());  // per family, per group
    for (std::size_t f = 0; f < in.families.size(); ++f) {
        const EmpiricalFamily& fam = in.families[f];
        std::vector<Eigen::Index> index(fam.terms.size(), -1);
        for (std::size_t k = 0; k < fam.terms.size(); ++k) {
            const EmpiricalTerm& t = fam.terms[k];
            if (std::any_of(in.learned.begin(), in.learned.end(), [&t](const LearnedTerm& l) { return l.term == t; }))
                continue;
            Eigen::VectorXd raw = term_column(in.readings, in.basis, t);
            const double norm = raw.norm();
            if (!(norm > 0)) continue;
            index[k] = static_cast<Eigen::Index>(cols.size());
            cols.push_back({f, t, std::move(raw), norm});
        }
        for (const auto& g : fam.groups) {
            std::vector<Eigen::Index> members;
            for (std::size_t k : g)
                if (index[k] >= 0) members.push_back(index[k]);
            if (!members.empty()) groups[f].push_back(members);
        }
    }
    const auto q = static_cast<Eigen::Index>(cols.size());
    if (q == 0) return out;
    Eigen::MatrixXd e(n, q);
    for (Eigen::Index j = 0; j < q; ++j)
        e.col(j) = cols[static_cast<std::size_t>(j)].raw / cols[static_cast<std::size_t>(j)].norm;

    // Project the model out: P = EᵀE − EᵀJ (JᵀJ)⁺ JᵀE, t = Eᵀr − EᵀJ (JᵀJ)⁺ Jᵀr.
    const Eigen::MatrixXd gem = e.transpose() * in.model_jac;
    const Eigen::MatrixXd gpinv = pinv_psd_relative(in.model_gram);
    const Eigen::MatrixXd p = e.transpose() * e - gem * gpinv * gem.transpose();
    const Eigen::VectorXd t =
        e.transpose() * in.residual_mm - gem * (gpinv * (in.model_jac.transpose() * in.residual_mm));

    // Terms the model already makes (independence below min_independence) are not searched.
    const double tol = in.min_independence * in.min_independence;
    std::vector<bool> ok(static_cast<std::size_t>(q), true);
    for (Eigen::Index j = 0; j < q; ++j)
        if (std::sqrt(std::max(p(j, j), 0.0)) < in.min_independence) {
            ok[static_cast<std::size_t>(j)] = false;
            out.not_searchable.push_back(cols[static_cast<std::size_t>(j)].term.name());
        }
    std::vector<Eigen::Index> all;
    for (Eigen::Index j = 0; j < q; ++j)
        if (ok[static_cast<std::size_t>(j)]) all.push_back(j);
    std::size_t group_count = 0;
    for (auto& fg : groups) {
        for (auto& g : fg)
            g.erase(
                std::remove_if(g.begin(), g.end(), [&ok](Eigen::Index j) { return !ok[static_cast<std::size_t>(j)]; }),
                g.end());
        fg.erase(std::remove_if(fg.begin(), fg.end(), [](const auto& g) { return g.empty(); }), fg.end());
        group_count += fg.size();
    }
    if (all.empty() || group_count == 0) return out;

    // The noise variance with every searchable term added (rank-aware).
    const double rss = in.residual_mm.squaredNorm();
    double reduction = 0;
    int rank = 0;
    {
        const Eigen::MatrixXd pa = sub(p, all);
        const Eigen::VectorXd ta = sub(t, all);
        const Eigen::VectorXd d = pa.diagonal().cwiseSqrt().cwiseInverse();
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(d.asDiagonal() * pa * d.asDiagonal());
        const Eigen::VectorXd pt = es.eigenvectors().transpose() * (d.asDiagonal() * ta);
        for (Eigen::Index k = 0; k < pt.size(); ++k)
            if (es.eigenvalues()[k] > tol) {
                reduction += pt[k] * pt[k] / es.eigenvalues()[k];
                ++rank;
            }
    }
    const double dof = static_cast<double>(n) - static_cast<double>(in.model_jac.cols()) - rank;
    if (dof < 1) return out;
    const double sigma2 = std::max(rss - reduction, 1e-300) / dof;
    const double alpha_g = in.alpha / static_cast<double>(group_count);

    auto explained = [&](const std::vector<Eigen::Index>& idx, bool* ok_rank) {
        const Eigen::MatrixXd ps = sub(p, idx);
        if (idx.size() > 1 && min_scaled_eigen(ps) < tol) {
            *ok_rank = false;
            return 0.0;
        }
        *ok_rank = true;
        const Eigen::VectorXd ts = sub(t, idx);
        return ts.dot(ps.ldlt().solve(ts));
    };

    std::vector<std::vector<Eigen::Index>> chosen(in.families.size());
    int best_family = -1;
    double best_score = 0;
    for (std::size_t f = 0; f < in.families.size(); ++f) {
        FamilyScore fs;
        fs.family = in.families[f].id;
        fs.variable = in.families[f].variable;
        std::vector<Eigen::Index> s;
        std::vector<bool> used(groups[f].size(), false);
        double red_s = 0, penalty = 0;
        for (;;) {
            int pick = -1;
            double pick_inc = 0, pick_red = 0, pick_pen = 0;
            for (std::size_t g = 0; g < groups[f].size(); ++g) {
                if (used[g]) continue;
                std::vector<Eigen::Index> idx = s;
                idx.insert(idx.end(), groups[f][g].begin(), groups[f][g].end());
                bool full_rank = false;
                const double red = explained(idx, &full_rank);
                if (!full_rank) continue;
                const double inc = red - red_s;
                const auto qg = static_cast<double>(groups[f][g].size());
                const double fval = inc / qg / sigma2;
                if (f_distribution_sf(fval, qg, dof) < alpha_g && inc > pick_inc) {
                    pick = static_cast<int>(g);
                    pick_inc = inc;
                    pick_red = red;
                    pick_pen = qg * f_critical(alpha_g, qg, dof);
                }
            }
            if (pick < 0) break;
            used[static_cast<std::size_t>(pick)] = true;
            s.insert(s.end(), groups[f][static_cast<std::size_t>(pick)].begin(),
                     groups[f][static_cast<std::size_t>(pick)].end());
            red_s = pick_red;
            penalty += pick_pen;
        }
        fs.delta_rss_mm2 = red_s;
        fs.dof1 = static_cast<double>(s.size());
        fs.dof2 = dof;
        fs.passes = !s.empty();
        if (fs.passes) {
            fs.f = red_s / fs.dof1 / sigma2;
            fs.p_value = f_distribution_sf(fs.f, fs.dof1, dof);
            fs.score = red_s / sigma2 - penalty;
        } else {
            // The best single group, for the table.
            for (const auto& g : groups[f]) {
                bool full_rank = false;
                const double red = explained(g, &full_rank);
                if (!full_rank) continue;
                const double fv = red / static_cast<double>(g.size()) / sigma2;
                if (fv > fs.f) {
                    fs.f = fv;
                    fs.dof1 = static_cast<double>(g.size());
                    fs.p_value = f_distribution_sf(fv, fs.dof1, dof);
                    fs.delta_rss_mm2 = red;
                }
            }
        }
        for (Eigen::Index j : s) fs.terms.push_back(cols[static_cast<std::size_t>(j)].term.name());
        if (fs.passes && fs.score > best_score) {
            best_score = fs.score;
            best_family = static_cast<int>(f);
        }
        chosen[f] = s;
        if (fs.passes && fs.score > best_score) out.penalty = penalty;
        out.step.families.push_back(fs);
    }
    std::stable_sort(out.step.families.begin(), out.step.families.end(),
                     [](const FamilyScore& a, const FamilyScore& b) {
                         if (a.passes != b.passes) return a.passes;
                         return a.passes ? a.score > b.score : a.f > b.f;
                     });
    if (best_family < 0) return out;

    const auto& s = chosen[static_cast<std::size_t>(best_family)];
    const Eigen::MatrixXd ps = sub(p, s);
    const Eigen::VectorXd ts = sub(t, s);
    const Eigen::MatrixXd inv = ps.ldlt().solve(Eigen::MatrixXd::Identity(ps.rows(), ps.cols()));
    const Eigen::VectorXd c = inv * ts;
    EmpiricalStep& st = out.step;
    st.family = in.families[static_cast<std::size_t>(best_family)].id;
    st.variable = in.families[static_cast<std::size_t>(best_family)].variable;
    for (std::size_t k = 0; k < s.size(); ++k) {
        const Col& col = cols[static_cast<std::size_t>(s[k])];
        const auto kk = static_cast<Eigen::Index>(k);
        st.terms.push_back({col.term, c[kk] / col.norm, std::sqrt(sigma2 * inv(kk, kk)) / col.norm});
        out.columns.push_back(col.raw);
    }
    for (const FamilyScore& fs : st.families)
        if (fs.family == st.family) {
            st.f = fs.f;
            st.p_value = fs.p_value;
            st.dof1 = fs.dof1;
            st.dof2 = fs.dof2;
        }
    st.threshold_p = alpha_g;
    out.score = best_score;
    for (const FamilyScore& fs : st.families)
        if (fs.family == st.family) out.delta_rss_mm2 = fs.delta_rss_mm2;
    out.found = true;
    return out;
}

VariableTrend term_trend(const ReadingSet& readings, const TermBasis& basis, const EmpiricalTerm& main,
                         const Eigen::VectorXd& residual_mm, std::string* unit, std::string* label) {
    const auto n = static_cast<Eigen::Index>(readings.readings.size());
    Eigen::VectorXd s = Eigen::VectorXd::Ones(n);
    std::vector<double> x(static_cast<std::size_t>(n), 0.0);
    double y_factor = 1e3;  // mm → µm
    *unit = "µm";
    int bins = 8;
    bool equal_width = false;
    auto grad_of = [&basis](Param p) -> Eigen::VectorXd {
        const auto it = std::find(basis.grad_params.begin(), basis.grad_params.end(), p);
        if (it == basis.grad_params.end()) return Eigen::VectorXd::Zero(basis.grad.rows());
        return basis.grad.col(static_cast<Eigen::Index>(it - basis.grad_params.begin()));
    };
    auto dir_col = [&basis](char d) { return Eigen::VectorXd(basis.u.col(d == 'x' ? 0 : d == 'y' ? 1 : 2)); };
    const std::string ax(1, main.axis);
    for (Eigen::Index i = 0; i < n; ++i) {
        const Reading& r = readings.readings[static_cast<std::size_t>(i)];
        double v = 0;
        switch (main.kind) {
            case EmpiricalKind::rotary_angular: {
                const double a = main.axis == 'A' ? r.pose.A_rad : main.axis == 'B' ? r.pose.B_rad : r.pose.C_rad;
                v = rad_to_deg(a);
                v = std::fmod(std::fmod(v, 360.0) + 360.0, 360.0);
                break;
            }
            case EmpiricalKind::rotary_backlash: {
                const auto& d = main.axis == 'A' ? basis.dir_a : main.axis == 'B' ? basis.dir_b : basis.dir_c;
                v = d.empty() ? 0.0 : d[static_cast<std::size_t>(i)];
                break;
            }
            case EmpiricalKind::linear_positioning:
                v = main.axis == 'X' ? r.pose.X_mm : main.axis == 'Y' ? r.pose.Y_mm : r.pose.Z_mm;
                break;
            case EmpiricalKind::location_drift:
            case EmpiricalKind::pivot_drift:
                v = r.time_s / 60.0;
                break;
            case EmpiricalKind::bar_temp_pivot:
            case EmpiricalKind::bar_temp_quadratic:
                v = r.bar_temp_C.value_or(20.0);
                break;
            case EmpiricalKind::air_temp_pivot:
                v = r.air_temp_C.value_or(20.0);
                break;
            case EmpiricalKind::tool_offset:
                v = basis.u(i, main.axis == 'x' ? 0 : main.axis == 'y' ? 1 : 2);
                break;
        }
        x[static_cast<std::size_t>(i)] = v;
    }
    switch (main.kind) {
        case EmpiricalKind::rotary_angular:
            s = grad_of(main.axis == 'A' ? Param::A_zero : main.axis == 'B' ? Param::B_zero : Param::C_zero);
            y_factor = 1e6;
            *unit = "µrad";
            *label = ax + " angular error";
            bins = 12;
            equal_width = true;
            break;
        case EmpiricalKind::rotary_backlash:
            s = grad_of(main.axis == 'A' ? Param::A_zero : main.axis == 'B' ? Param::B_zero : Param::C_zero);
            y_factor = 1e6;
            *unit = "µrad";
            *label = ax + " angle error";
            bins = 2;
            equal_width = true;
            break;
        case EmpiricalKind::linear_positioning:
            s = dir_col(static_cast<char>(main.axis - 'X' + 'x'));
            *label = ax + " positioning error";
            break;
        case EmpiricalKind::location_drift:
            s = grad_of(main.location);
            if (param_info(main.location).unit == ParamUnit::rad) {
                y_factor = 1e6;
                *unit = "µrad";
            }
            *label = std::string(param_info(main.location).name);
            break;
        case EmpiricalKind::pivot_drift:
        case EmpiricalKind::bar_temp_pivot:
        case EmpiricalKind::air_temp_pivot:
        case EmpiricalKind::tool_offset:
            s = dir_col(main.axis);
            *label = "pivot " + ax;
            break;
        case EmpiricalKind::bar_temp_quadratic:
            *label = "reading";
            break;
    }
    VariableTrend tr;
    std::vector<std::size_t> order(static_cast<std::size_t>(n));
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&x](std::size_t a, std::size_t b) { return x[a] < x[b]; });
    if (n == 0) return tr;
    const double lo = x[order.front()], hi = x[order.back()];
    auto bin_of = [&](std::size_t rank) -> int {
        if (!equal_width) return static_cast<int>(rank * static_cast<std::size_t>(bins) / static_cast<std::size_t>(n));
        const double xv = x[order[rank]];
        const double span = main.kind == EmpiricalKind::rotary_angular ? 360.0 : hi - lo;
        const double from = main.kind == EmpiricalKind::rotary_angular ? 0.0 : lo;
        if (!(span > 0)) return 0;
        return std::clamp(static_cast<int>((xv - from) / span * bins), 0, bins - 1);
    };
    std::vector<double> sx(static_cast<std::size_t>(bins), 0), ssr(sx), sss(sx), cnt(sx);
    for (std::size_t k = 0; k < order.size(); ++k) {
        const auto b = static_cast<std::size_t>(bin_of(k));
        const auto i = static_cast<Eigen::Index>(order[k]);
        sx[b] += x[order[k]];
        ssr[b] += s[i] * residual_mm[i];
        sss[b] += s[i] * s[i];
        cnt[b] += 1;
    }
    for (std::size_t b = 0; b < sx.size(); ++b) {
        if (cnt[b] == 0 || !(sss[b] > 0)) continue;
        tr.bin_centre.push_back(sx[b] / cnt[b]);
        tr.bin_mean_mm.push_back(ssr[b] / sss[b] * y_factor / 1e3);  // stored so that ×1e3 gives the unit
        tr.bin_count.push_back(cnt[b]);
    }
    return tr;
}

std::string describe(const std::string& family, std::span<const LearnedTerm> terms) {
    if (terms.empty()) return family;
    const EmpiricalTerm& t0 = terms.front().term;
    const std::string ax(1, t0.axis);
    std::string out;
    switch (t0.kind) {
        case EmpiricalKind::rotary_angular: {
            // Per order: ε = amp·cos(kθ − φ).
            std::vector<std::pair<double, std::string>> parts;
            for (int k = 1; k <= 9; ++k) {
                double a = 0, b = 0;
                bool any = false;
                for (const LearnedTerm& l : terms)
                    if (l.term.order == k) {
                        (l.term.sine ? b : a) = l.value;
                        any = true;
                    }
                if (!any) continue;
                const double amp = std::hypot(a, b);
                double phase = rad_to_deg(std::atan2(b, a));
                if (phase < 0) phase += 360;
                parts.emplace_back(-amp, std::string(per_revolution(k)) + " per revolution, " +
                                             number_format("%.3g", amp * 1e6) + " µrad, phase " +
                                             number_format("%.0f", phase) + "°");
            }
            std::sort(parts.begin(), parts.end());
            out = "the " + ax + " axis: ";
            for (std::size_t i = 0; i < parts.size(); ++i) out += (i ? "; " : "") + parts[i].second;
            return out;
        }
        case EmpiricalKind::rotary_backlash:
            return "the " + ax + " axis: backlash (reversal error) " +
                   number_format("%.3g", 2 * std::abs(terms[0].value) * 1e6) + " µrad";
        case EmpiricalKind::linear_positioning: {
            out = "the " + ax + " axis: non-linear positioning error,";
            for (const LearnedTerm& l : terms)
                out += std::string(l.term.order == 2   ? " quadratic "
                                   : l.term.order == 3 ? " cubic "
                                                       : " order-n ") +
                       number_format("%.3g", l.value * 1e3) + " µm at " + ax + " = 100 mm";
            return out;
        }
        default:
            break;
    }
    out = family == "time"            ? "drift during the test:"
          : family == "bar_direction" ? "a constant offset:"
                                      : "with " + family + ":";
    for (const LearnedTerm& l : terms) {
        const std::string u = l.term.unit();
        double f = 1;
        std::string shown = u;
        if (u == "mm_per_h") {
            f = 1e3;
            shown = "µm/h";
        } else if (u == "rad_per_h") {
            f = 1e6;
            shown = "µrad/h";
        } else if (u == "mm_per_K") {
            f = 1e3;
            shown = "µm/K";
        } else if (u == "mm") {
            f = 1e3;
            shown = "µm";
        }
        out += " " + l.term.name() + " " + number_format("%.3g", l.value * f) + " " + shown;
    }
    return out;
}

}  // namespace ballbar::analysis::detail
