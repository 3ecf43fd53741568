// SPDX-License-Identifier: MIT
// The diagnosis of a circular test: a least-squares fit of every effect's radial signature to the
// measured − programmed radius over the data arcs (docs/circular.md, "Method").
//
// Linear in the effects' sizes, except for the servo lag (an exact first-order model, linearised about
// the current estimate), the cyclic errors' pitches and the vibration's frequency (found by a search on
// the residual, then refined with the others by Gauss–Newton). Standard uncertainties are the
// covariance of the last linear solve scaled by the residual variance. Before fitting, the signatures
// are taken in priority order and any that is (nearly) a combination of those before it is reported
// unseparable instead of guessed.
#include "circular_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <unsupported/Eigen/FFT>

#include "ballbar/analysis/types.hpp"

namespace ballbar::analysis::circular::detail {
namespace {

constexpr double kSpikeDecay_s = 0.015;

enum Col : int {
    kConst,
    kCos,
    kSin,
    kBlP,
    kBlQ,
    kSpP,
    kSpQ,
    kScale,
    kSquare,
    kServo,
    kStrP,
    kStrQ,
    kBaseCount,
    kCycPs = kBaseCount,
    kCycPc,
    kCycQs,
    kCycQc,
    kVibS,
    kVibC,
    kDkP,
    kDkQ,
    kDf,
};

std::optional<Diag> col_diag(int col) {
    switch (col) {
        case kBlP:
            return Diag::BacklashP;
        case kBlQ:
            return Diag::BacklashQ;
        case kSpP:
            return Diag::SpikeP;
        case kSpQ:
            return Diag::SpikeQ;
        case kScale:
            return Diag::ScaleMismatch;
        case kSquare:
            return Diag::Squareness;
        case kServo:
            return Diag::ServoMismatch;
        case kStrP:
            return Diag::StraightnessP;
        case kStrQ:
            return Diag::StraightnessQ;
        default:
            return std::nullopt;
    }
}

struct State {
    double tau_mean_s = 0.0;
    double dtau_ms = 0.0;
    double kp = 0.0, kq = 0.0, f_hz = 0.0;  // 0: not in the model
    double ap_s = 0.0, ap_c = 0.0, aq_s = 0.0, aq_c = 0.0, av_s = 0.0, av_c = 0.0;
};

struct Design {
    std::vector<int> ids;
    Eigen::MatrixXd buffer;  ///< rows × the most columns a design has: allocated once, reused by every build
    Eigen::Index used = 0;   ///< columns in use
    Eigen::VectorXd y;
    double vib_f_hz = 0.0;  ///< the frequency vib_sin and vib_cos are for
    std::vector<double> vib_sin, vib_cos;
    auto x() { return buffer.leftCols(used); }
    auto x() const { return buffer.leftCols(used); }
    int col(int id) const {
        const auto it = std::find(ids.begin(), ids.end(), id);
        return it == ids.end() ? -1 : static_cast<int>(it - ids.begin());
    }
};

struct Solution {
    Eigen::VectorXd beta;
    Eigen::MatrixXd cov;
    Eigen::VectorXd residual;
    double rms = 0.0;
};

double spike_value(double angle, int dir, double start, double omega) {
    // angle: the axis's phase with reversals at multiples of π; the spike of the latest reversal,
    // when it happened on the arc (after the arc's start angle `start`, in the same phase).
    const double k = dir > 0 ? std::floor(angle / kPi) : std::ceil(angle / kPi);
    const double since = dir > 0 ? angle - k * kPi : k * kPi - angle;
    if (dir * (k * kPi - start) <= 1e-9) return 0.0;
    const double dt = since / omega;
    if (dt > 20.0 * kSpikeDecay_s) return 0.0;
    const double sign = (static_cast<long long>(std::llround(k)) % 2 == 0) ? 1.0 : -1.0;
    return sign * std::exp(-dt / kSpikeDecay_s);
}

class Model {
  public:
    Model(const FitInput& in) : in_(in), r_(in.test.radius_mm), w_(in.omega_rad_s) {
        double lo = in.points.front().t, hi = lo;
        for (const auto& p : in.points) lo = std::min(lo, p.t), hi = std::max(hi, p.t);
        t_mid_ = 0.5 * (lo + hi);
        for (std::size_t i = 1; i < in.points.size(); ++i)
            if (in.points[i].run == in.points[i - 1].run)
                path_mm_ += r_ * std::abs(in.points[i].theta - in.points[i - 1].theta);
    }

    /// The axes' steady-state response to the circle through first-order lags: amplitude and phase.
    struct Lag {
        double ap, aq, cp, sp, cq, sq;
    };
    Lag lag_of(double tau_p, double tau_q) const {
        const double php = std::atan(w_ * tau_p), phq = std::atan(w_ * tau_q);
        return {1.0 / std::hypot(1.0, w_ * tau_p),
                1.0 / std::hypot(1.0, w_ * tau_q),
                std::cos(php),
                std::sin(php),
                std::cos(phq),
                std::sin(phq)};
    }
    /// The design for the state `st` and the columns `ids`, and the data less the lag's deviation.
    /// Rows in blocks: first what several columns share, for a block of points, then each column's
    /// block in one loop (the columns are stored apart, so each loop writes one run of memory).
    /// With `first` > 0, `d` holds the columns ids[0, first) already and only the rest are built:
    /// the data (`d.y`) stays as it is, linearised where the design it extends was.
    void build(const State& st, const std::vector<int>& ids, Design& d, std::size_t first = 0) const {
        const auto n = static_cast<Eigen::Index>(in_.points.size());
        const auto m = static_cast<Eigen::Index>(ids.size());
        if (first > 0 &&
            !(d.used == static_cast<Eigen::Index>(first) && d.buffer.rows() == n &&
              std::equal(d.ids.begin(), d.ids.end(), ids.begin(), ids.begin() + static_cast<std::ptrdiff_t>(first))))
            throw CircularError("internal: a design extended by columns it does not hold");
        d.ids = ids;
        if (d.buffer.rows() != n || d.buffer.cols() < m) d.buffer.resize(n, std::max<Eigen::Index>(m, kDf + 1));
        d.used = m;
        const bool with_y = first == 0;
        if (with_y) d.y.resize(n);
        auto has = [&](int id) {
            return std::find(ids.begin() + static_cast<std::ptrdiff_t>(first), ids.end(), id) != ids.end();
        };
        const bool servo = has(kServo);
        const double tp = std::max(st.tau_mean_s + 0.5e-3 * st.dtau_ms, 0.0);
        const double tq = std::max(st.tau_mean_s - 0.5e-3 * st.dtau_ms, 0.0);
        const Lag lag0 = lag_of(tp, tq);
        // The servo column: the lag's deviation differentiated in the lag difference (τp = τ̄ + Δτ/2,
        // τq = τ̄ − Δτ/2). With u = ωτp, the p axis's share of the radius is c = (cos θ + dir·sin θ·u)/(1 + u²),
        // so dc/du = (dir·sin θ − 2u·c)/(1 + u²); the q axis's likewise, with v = ωτq and the other sign.
        const double u = w_ * tp, v = w_ * tq;
        const double ku = 1.0 / (1.0 + u * u), kv = 1.0 / (1.0 + v * v);
        const double servo_scale = 1e3 * r_ * 0.5e-3 * w_;  // µm per unit of dc, and dτp/dΔτ (ms → s)
        const double phm = std::atan(w_ * st.tau_mean_s);
        const double cm = std::cos(phm), sm = std::sin(phm);
        const double php = std::atan(w_ * tp), phq = std::atan(w_ * tq);
        // The periodic terms' sine and cosine once per point for all their columns (values, derivatives).
        const bool cyc_p = has(kCycPs) || has(kCycPc) || has(kDkP);
        const bool cyc_q = has(kCycQs) || has(kCycQc) || has(kDkQ);
        const bool vib = has(kVibS) || has(kVibC) || has(kDf);
        // The vibration's phase depends on time and frequency only: kept while the frequency is.
        if (vib && !(d.vib_f_hz == st.f_hz && d.vib_sin.size() == in_.points.size())) {
            d.vib_f_hz = st.f_hz;
            d.vib_sin.resize(in_.points.size()), d.vib_cos.resize(in_.points.size());
            for (std::size_t i = 0; i < in_.points.size(); ++i) {
                const double a = 2.0 * kPi * st.f_hz * (in_.points[i].t - t_mid_);
                d.vib_sin[i] = std::sin(a), d.vib_cos[i] = std::cos(a);
            }
        }
        constexpr Eigen::Index kBlock = 256;
        double ca[kBlock], sa[kBlock], spx[kBlock], cqx[kBlock], xp[kBlock], xq[kBlock], servo_col[kBlock];
        double sin_p[kBlock], cos_p[kBlock], sin_q[kBlock], cos_q[kBlock];
        for (Eigen::Index b0 = 0; b0 < n; b0 += kBlock) {
            const Eigen::Index len = std::min(kBlock, n - b0);
            const FitPoint* pts = in_.points.data() + b0;
            for (Eigen::Index j = 0; j < len; ++j) {
                const FitPoint& pt = pts[j];
                const double c0 = pt.cos_theta, s0 = pt.sin_theta;
                const int dir = pt.dir;
                // cos and sin of θ − dir·φ for the mean lag and for each axis's own.
                ca[j] = c0 * cm + dir * s0 * sm, sa[j] = s0 * cm - dir * c0 * sm;
                const double cpx = c0 * lag0.cp + dir * s0 * lag0.sp;
                spx[j] = s0 * lag0.cp - dir * c0 * lag0.sp;
                cqx[j] = c0 * lag0.cq + dir * s0 * lag0.sq;
                const double sqx = s0 * lag0.cq - dir * c0 * lag0.sq;
                servo_col[j] = 0.0;
                if (servo || with_y) {
                    // The lags' radial deviation (µm) is 1e3·R·(|(c, s)| − 1): the axes' shares of the radius
                    // through their lags' amplitude and phase.
                    const double c = lag0.ap * cpx, s = lag0.aq * sqx;
                    const double norm = std::sqrt(c * c + s * s);
                    if (servo && norm > 0.0)  // 0 only for a lag beyond any machine's (ωτ > 1e150)
                        servo_col[j] = servo_scale *
                                       (c * (dir * s0 - 2.0 * u * c) * ku + s * (dir * c0 + 2.0 * v * s) * kv) / norm;
                    if (with_y) d.y[b0 + j] = pt.y_um - (1e3 * r_ * (norm - 1.0) - servo_col[j] * st.dtau_ms);
                }
                // Cyclic phases about the centre: the same family as about the origin, better conditioned in k.
                xp[j] = r_ * cpx, xq[j] = r_ * sqx;
                if (cyc_p) {
                    const double a = 2.0 * kPi * st.kp * xp[j];
                    sin_p[j] = std::sin(a), cos_p[j] = std::cos(a);
                }
                if (cyc_q) {
                    const double a = 2.0 * kPi * st.kq * xq[j];
                    sin_q[j] = std::sin(a), cos_q[j] = std::cos(a);
                }
            }
            const double* vs = vib ? d.vib_sin.data() + b0 : nullptr;
            const double* vc = vib ? d.vib_cos.data() + b0 : nullptr;
            for (auto c = static_cast<Eigen::Index>(first); c < m; ++c) {
                double* col = d.buffer.col(c).data() + b0;
                switch (ids[static_cast<std::size_t>(c)]) {
                    case kConst:
                        for (Eigen::Index j = 0; j < len; ++j) col[j] = 1.0;
                        break;
                    case kCos:
                        for (Eigen::Index j = 0; j < len; ++j) col[j] = ca[j];
                        break;
                    case kSin:
                        for (Eigen::Index j = 0; j < len; ++j) col[j] = sa[j];
                        break;
                    case kBlP:
                        for (Eigen::Index j = 0; j < len; ++j)
                            col[j] = 0.5 * pts[j].dir * (spx[j] >= 0.0 ? 1.0 : -1.0) * ca[j];
                        break;
                    case kBlQ:
                        for (Eigen::Index j = 0; j < len; ++j)
                            col[j] = -0.5 * pts[j].dir * (cqx[j] >= 0.0 ? 1.0 : -1.0) * sa[j];
                        break;
                    case kSpP:
                        for (Eigen::Index j = 0; j < len; ++j) {
                            const FitPoint& pt = pts[j];
                            const double start = pt.theta - pt.dir * pt.travelled;
                            col[j] = spike_value(pt.theta - pt.dir * php, pt.dir, start, w_) * ca[j];
                        }
                        break;
                    case kSpQ:
                        for (Eigen::Index j = 0; j < len; ++j) {
                            const FitPoint& pt = pts[j];
                            const double start = pt.theta - pt.dir * pt.travelled;
                            col[j] =
                                spike_value(pt.theta - pt.dir * phq - 0.5 * kPi, pt.dir, start - 0.5 * kPi, w_) * sa[j];
                        }
                        break;
                    case kScale:
                        for (Eigen::Index j = 0; j < len; ++j)
                            col[j] = r_ * 1e-3 * 0.5 * (ca[j] * ca[j] - sa[j] * sa[j]);
                        break;
                    case kSquare:
                        // e_p = α·q with q = q_c + R sin θ: the q_c·cos θ part moves the circle's centre
                        // only (the centre's column), so the signature is what is left, R·sin θ·cos θ.
                        for (Eigen::Index j = 0; j < len; ++j) col[j] = 1e-3 * r_ * sa[j] * ca[j];
                        break;
                    case kServo:
                        for (Eigen::Index j = 0; j < len; ++j) col[j] = servo_col[j];
                        break;
                    case kStrP:
                        for (Eigen::Index j = 0; j < len; ++j) col[j] = ca[j] * ca[j] * sa[j];
                        break;
                    case kStrQ:
                        for (Eigen::Index j = 0; j < len; ++j) col[j] = sa[j] * sa[j] * ca[j];
                        break;
                    case kCycPs:
                        for (Eigen::Index j = 0; j < len; ++j) col[j] = sin_p[j] * ca[j];
                        break;
                    case kCycPc:
                        for (Eigen::Index j = 0; j < len; ++j) col[j] = cos_p[j] * ca[j];
                        break;
                    case kCycQs:
                        for (Eigen::Index j = 0; j < len; ++j) col[j] = sin_q[j] * sa[j];
                        break;
                    case kCycQc:
                        for (Eigen::Index j = 0; j < len; ++j) col[j] = cos_q[j] * sa[j];
                        break;
                    case kVibS:
                        for (Eigen::Index j = 0; j < len; ++j) col[j] = vs[j];
                        break;
                    case kVibC:
                        for (Eigen::Index j = 0; j < len; ++j) col[j] = vc[j];
                        break;
                    case kDkP:
                        for (Eigen::Index j = 0; j < len; ++j)
                            col[j] = 2.0 * kPi * xp[j] * (st.ap_s * cos_p[j] - st.ap_c * sin_p[j]) * ca[j];
                        break;
                    case kDkQ:
                        for (Eigen::Index j = 0; j < len; ++j)
                            col[j] = 2.0 * kPi * xq[j] * (st.aq_s * cos_q[j] - st.aq_c * sin_q[j]) * sa[j];
                        break;
                    case kDf:
                        for (Eigen::Index j = 0; j < len; ++j)
                            col[j] = 2.0 * kPi * (pts[j].t - t_mid_) * (st.av_s * vc[j] - st.av_c * vs[j]);
                        break;
                    default:
                        for (Eigen::Index j = 0; j < len; ++j) col[j] = 0.0;
                        break;
                }
            }
        }
    }

    /// The lag phase of an axis (its own lag) and of the mean lag: cos and sin, for the two below.
    struct AxisPhase {
        double c_axis, s_axis, c_mean, s_mean;
    };
    AxisPhase axis_phase(const State& st, int axis) const {
        const double tau = std::max(st.tau_mean_s + (axis == 0 ? 0.5e-3 : -0.5e-3) * st.dtau_ms, 0.0);
        const double ph = std::atan(w_ * tau), pm = std::atan(w_ * st.tau_mean_s);
        return {std::cos(ph), std::sin(ph), std::cos(pm), std::sin(pm)};
    }
    /// The axis's position about the centre (mm), R·cos or R·sin of θ − dir·φ_axis.
    double axis_position(const FitPoint& pt, const AxisPhase& ph, int axis) const {
        return axis == 0 ? r_ * (pt.cos_theta * ph.c_axis + pt.dir * pt.sin_theta * ph.s_axis)
                         : r_ * (pt.sin_theta * ph.c_axis - pt.dir * pt.cos_theta * ph.s_axis);
    }
    /// The share of the axis's error in the radius: cos or sin of θ − dir·φ_mean.
    double radial_factor(const FitPoint& pt, const AxisPhase& ph, int axis) const {
        return axis == 0 ? pt.cos_theta * ph.c_mean + pt.dir * pt.sin_theta * ph.s_mean
                         : pt.sin_theta * ph.c_mean - pt.dir * pt.cos_theta * ph.s_mean;
    }
    double radius() const { return r_; }
    /// Axis travel along the data, at most (|dp| ≤ R dθ).
    double path_mm() const { return path_mm_; }
    double t_mid() const { return t_mid_; }

  private:
    const FitInput& in_;
    double r_, w_, t_mid_ = 0.0, path_mm_ = 0.0;
};

/// The normal equations of a design: XᵀX (whole, not only a triangle) and Xᵀy.
struct Normal {
    Eigen::MatrixXd a;
    Eigen::VectorXd b;
};

/// XᵀX of the design, whole: a symmetric rank update (half the products) made symmetric.
Eigen::MatrixXd gram(const Design& d) {
    const Eigen::Index m = d.x().cols();
    Eigen::MatrixXd g = Eigen::MatrixXd::Zero(m, m);
    g.selfadjointView<Eigen::Lower>().rankUpdate(d.x().transpose());
    return g.selfadjointView<Eigen::Lower>();
}

/// The normal equations of the whole design.
void normal_full(const Design& d, Normal& ne) {
    ne.a = gram(d);
    ne.b = d.x().transpose() * d.y;
}

/// `ne` holds the normal equations of the design's first `from` columns, and columns were appended
/// since (the data unchanged): only the products with the new columns are computed.
void normal_append(const Design& d, Eigen::Index from, Normal& ne) {
    const Eigen::Index m = d.x().cols(), k = m - from;
    const auto added = d.buffer.middleCols(from, k);
    const Eigen::MatrixXd cross = d.x().transpose() * added;  // m × k: the new columns against all
    Eigen::MatrixXd a(m, m);
    a.topLeftCorner(from, from) = ne.a;
    a.rightCols(k) = cross;
    a.bottomLeftCorner(k, from) = cross.topRows(from).transpose();
    ne.a = std::move(a);
    ne.b.conservativeResize(m);
    ne.b.tail(k) = added.transpose() * d.y;
}

/// Least squares on the design from its normal equations, into `s` (its vectors reused from the
/// last solve: no new n-long ones).
void solve(const Design& d, const Normal& ne, Solution& s) {
    const Eigen::Index m = d.x().cols(), n = d.x().rows();
    const Eigen::MatrixXd& a = ne.a;
    Eigen::VectorXd scale = a.diagonal().cwiseSqrt().cwiseMax(1e-300).cwiseInverse();
    const Eigen::MatrixXd as = scale.asDiagonal() * a * scale.asDiagonal();
    const Eigen::VectorXd b = scale.asDiagonal() * ne.b;
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(as);
    s.beta = scale.asDiagonal() * ldlt.solve(b);
    s.residual = d.y;
    s.residual.noalias() -= d.x() * s.beta;  // in place: no n-long temporary
    const double rss = s.residual.squaredNorm();
    s.rms = std::sqrt(rss / static_cast<double>(std::max<Eigen::Index>(n, 1)));
    const double var = rss / static_cast<double>(std::max<Eigen::Index>(n - m, 1));
    s.cov = var * (scale.asDiagonal() * ldlt.solve(Eigen::MatrixXd::Identity(m, m)) * scale.asDiagonal());
}

std::string col_name(int id, Plane plane) {
    if (id == kConst) return "mean radius";
    if (id == kCos || id == kSin) return "centre";
    const auto diag = col_diag(id);
    return diag ? diagnostic_key(*diag, plane) : "?";
}

struct Separability {
    std::vector<int> accepted;
    std::vector<UnseparableGroup> groups;
    std::vector<int> confounded;  // accepted columns whose value stands for a group's combination
};

/// Takes the base signatures in priority order; one nearly a combination of the accepted ones is
/// unseparable, grouped with those it combines.
Separability check_separability(const Design& d, const FitInput& in, const AnalysisOptions& opt) {
    Separability out;
    const Eigen::Index m = d.x().cols();
    Eigen::MatrixXd g = gram(d);
    const Eigen::VectorXd nrm = g.diagonal().cwiseSqrt().cwiseMax(1e-300);
    for (Eigen::Index i = 0; i < m; ++i)
        for (Eigen::Index j = 0; j < m; ++j) g(i, j) /= nrm[i] * nrm[j];
    std::vector<Eigen::Index> acc;
    for (Eigen::Index j = 0; j < m; ++j) {
        const int id = d.ids[static_cast<std::size_t>(j)];
        if (nrm[j] < 1e-9 * std::sqrt(static_cast<double>(d.x().rows()))) {
            UnseparableGroup none;
            none.keys = {col_name(id, in.test.plane)};
            none.reason = "no signature in this data";
            out.groups.push_back(none);
            continue;
        }
        if (acc.empty()) {
            acc.push_back(j);
            continue;
        }
        const auto k = static_cast<Eigen::Index>(acc.size());
        Eigen::MatrixXd gss(k, k);
        Eigen::VectorXd gjs(k);
        for (Eigen::Index a = 0; a < k; ++a) {
            gjs[a] = g(acc[static_cast<std::size_t>(a)], j);
            for (Eigen::Index b = 0; b < k; ++b)
                gss(a, b) = g(acc[static_cast<std::size_t>(a)], acc[static_cast<std::size_t>(b)]);
        }
        const Eigen::VectorXd c = gss.ldlt().solve(gjs);
        const double independence = std::sqrt(std::max(1.0 - gjs.dot(c), 0.0));
        if (independence >= opt.min_independence) {
            acc.push_back(j);
            continue;
        }
        UnseparableGroup grp;
        grp.keys.push_back(col_name(id, in.test.plane));
        const double cmax = c.cwiseAbs().maxCoeff();
        for (Eigen::Index a = 0; a < k; ++a) {
            if (std::abs(c[a]) < 0.1 * cmax) continue;
            const int aid = d.ids[static_cast<std::size_t>(acc[static_cast<std::size_t>(a)])];
            const std::string name = col_name(aid, in.test.plane);
            if (std::find(grp.keys.begin(), grp.keys.end(), name) == grp.keys.end()) grp.keys.push_back(name);
            if (col_diag(aid)) {
                out.confounded.push_back(aid);
                grp.combined_key = name;
            }
        }
        grp.reason = in.both_directions ? "their radial signatures coincide over this data arc"
                                        : "one direction only: their radial signatures coincide";
        out.groups.push_back(grp);
    }
    for (auto j : acc) out.accepted.push_back(d.ids[static_cast<std::size_t>(j)]);
    return out;
}

struct Peak {
    double k = 0.0;
    double amp = 0.0;
    double strength = 0.0;  ///< RMS of its radial signature, to compare candidates
    bool found = false;
};

/// The sums of one grid frequency's 2×2 fit, each weighted: sin², sin·cos, y·sin, y·cos (cos² is the
/// weights' squares less sin²).
struct GridSums {
    double ss = 0, sc = 0, ys = 0, yc = 0;
};

/// One grid frequency's sums in one pass over the points, two points at a time in the two lanes of a
/// packet (SSE2 on any x86-64), each lane summing half the points; each point's weighted phasor
/// (zr, zi) = w·(cos, sin) is then turned by one grid step (sr, si) for the next frequency. m is even
/// (the arrays are padded with a point of weight 0, which adds exactly nothing).
/// The packet is the compiler's own two-double vector (GCC and Clang), not Eigen's two-element array:
/// the same sums, and a sanitizer build, which inlines little, does not make a function call per
/// element (with Eigen this loop was half of the sanitizer build's circular test).
GridSums grid_sums(std::size_t m, const double* y, const double* sr, const double* si, double* zr, double* zi) {
    using Lane = double __attribute__((vector_size(16)));
    const auto load = [](const double* p) {
        Lane v;
        std::memcpy(&v, p, sizeof v);
        return v;
    };
    Lane ss = {0.0, 0.0}, sc = ss, ys = ss, yc = ss;
    for (std::size_t i = 0; i < m; i += 2) {
        const Lane re = load(zr + i), im = load(zi + i), yi = load(y + i), c_step = load(sr + i), s_step = load(si + i);
        ss += im * im, sc += im * re, ys += yi * im, yc += yi * re;
        const Lane re_next = re * c_step - im * s_step, im_next = re * s_step + im * c_step;
        std::memcpy(zr + i, &re_next, sizeof re_next), std::memcpy(zi + i, &im_next, sizeof im_next);
    }
    return {ss[0] + ss[1], sc[0] + sc[1], ys[0] + ys[1], yc[0] + yc[1]};
}

/// Searches the residual for a cyclic error of one axis: 2×2 fits over a grid of spatial
/// frequencies (a rotating phasor per point makes each step a multiplication), then golden section.
Peak search_cyclic(const FitInput& in, const Model& model, const State& st, const Eigen::VectorXd& resid, int axis,
                   const AnalysisOptions& opt) {
    Peak peak;
    const double r = model.radius();
    const double kmin = 4.0 / r, kmax = 1.0 / opt.min_pitch_mm;
    if (kmin >= kmax) return peak;
    const std::size_t n = in.points.size();
    // The search samples each cycle at least 6 times along the axis travel.
    const double wanted = std::max(2000.0, 6.0 * kmax * model.path_mm());
    const std::size_t stride = std::max<std::size_t>(1, static_cast<std::size_t>(static_cast<double>(n) / wanted));
    std::vector<double> x, w, y;
    const Model::AxisPhase phase = model.axis_phase(st, axis);
    for (std::size_t i = 0; i < n; i += stride) {
        x.push_back(model.axis_position(in.points[i], phase, axis));
        w.push_back(model.radial_factor(in.points[i], phase, axis));
        y.push_back(resid[static_cast<Eigen::Index>(i)]);
    }
    const std::size_t m = x.size();
    auto reduction_at = [&](double k, double* as, double* ac) {
        double sss = 0, ssc = 0, scc = 0, sys = 0, syc = 0;
        for (std::size_t i = 0; i < m; ++i) {
            const double a = 2.0 * kPi * k * x[i];
            const double s = std::sin(a) * w[i], c = std::cos(a) * w[i];
            sss += s * s, ssc += s * c, scc += c * c, sys += y[i] * s, syc += y[i] * c;
        }
        const double det = sss * scc - ssc * ssc;
        if (det <= 0.0) return 0.0;
        const double bs = (scc * sys - ssc * syc) / det, bc = (sss * syc - ssc * sys) / det;
        if (as) *as = bs, *ac = bc;
        return bs * sys + bc * syc;
    };
    const double dk = 1.0 / (8.0 * r);
    // A rotating phasor per point (real and imaginary parts apart: plain multiplications, no complex
    // library calls), advanced by one grid step each pass.
    // Even length for the two lanes of grid_sums: a last point of weight 0 if m is odd.
    const std::size_t m2 = m + (m % 2);
    w.resize(m2, 0.0), y.resize(m2, 0.0);
    std::vector<double> zr(m2, 0.0), zi(m2, 0.0), sr(m2, 1.0), si(m2, 0.0);
    double ww = 0.0;
    for (std::size_t i = 0; i < m; ++i) {
        zr[i] = w[i] * std::cos(2.0 * kPi * kmin * x[i]), zi[i] = w[i] * std::sin(2.0 * kPi * kmin * x[i]);
        sr[i] = std::cos(2.0 * kPi * dk * x[i]), si[i] = std::sin(2.0 * kPi * dk * x[i]);
        ww += w[i] * w[i];
    }
    double best = -1.0, best_k = kmin;
    for (double k = kmin; k <= kmax; k += dk) {
        const auto [sss, ssc, sys, syc] = grid_sums(m2, y.data(), sr.data(), si.data(), zr.data(), zi.data());
        const double scc = ww - sss;
        const double det = sss * scc - ssc * ssc;
        if (det <= 0.0) continue;
        const double red = ((scc * sys - ssc * syc) * sys + (sss * syc - ssc * sys) * syc) / det;
        if (red > best) best = red, best_k = k;
    }
    // Golden section about the grid's best: 10 steps narrow the two grid steps to 2 % of one, from
    // where the Gauss–Newton step on the pitch (fit_diagnostics) converges.
    double lo = std::max(kmin, best_k - dk), hi = std::min(kmax, best_k + dk);
    const double gr = (std::sqrt(5.0) - 1.0) / 2.0;
    double a = hi - gr * (hi - lo), b = lo + gr * (hi - lo);
    double fa = reduction_at(a, nullptr, nullptr), fb = reduction_at(b, nullptr, nullptr);
    for (int it = 0; it < 10; ++it) {
        if (fa > fb) {
            hi = b, b = a, fb = fa, a = hi - gr * (hi - lo), fa = reduction_at(a, nullptr, nullptr);
        } else {
            lo = a, a = b, fa = fb, b = lo + gr * (hi - lo), fb = reduction_at(b, nullptr, nullptr);
        }
    }
    peak.k = 0.5 * (lo + hi);
    double as = 0.0, ac = 0.0;
    const double red = reduction_at(peak.k, &as, &ac);
    peak.amp = std::hypot(as, ac);
    double yy = 0.0;
    for (std::size_t i = 0; i < m; ++i) yy += y[i] * y[i];
    const double sigma = std::sqrt(std::max(yy - red, 0.0) / static_cast<double>(std::max<std::size_t>(m, 3) - 2));
    const double amp_sigma = sigma * std::sqrt(2.0 / std::max(ww, 1e-300));
    peak.found = peak.amp > 6.0 * amp_sigma && peak.amp > 0.1;
    peak.strength = peak.amp * std::sqrt(ww / (2.0 * static_cast<double>(m)));
    return peak;
}

/// Searches the residual for a vibration: the largest line of its spectrum on a uniform time grid.
/// `fft` keeps its plan (the twiddle factors) between the searches of one fit: they are all the same size.
Peak search_vibration(const FitInput& in, const Eigen::VectorXd& resid, const AnalysisOptions& opt,
                      Eigen::FFT<double>& fft) {
    Peak peak;
    const double fs = in.sample_rate_hz;
    if (!(fs > 0.0)) return peak;
    const double dt = 1.0 / fs;
    double t0 = in.points.front().t, t1 = t0;
    for (const auto& p : in.points) t0 = std::min(t0, p.t), t1 = std::max(t1, p.t);
    const auto cells = static_cast<std::size_t>(std::llround((t1 - t0) / dt)) + 1;
    if (cells > (std::size_t{1} << 24)) return peak;  // 4.6 h at 1 kHz: beyond any circular test
    std::size_t nfft = 1;
    while (nfft < cells) nfft <<= 1;
    std::vector<double> grid(nfft, 0.0);
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        const auto cell = static_cast<std::size_t>(std::llround((in.points[i].t - t0) / dt));
        if (cell < nfft) grid[cell] = resid[static_cast<Eigen::Index>(i)];
    }
    std::vector<std::complex<double>> spec;
    fft.fwd(spec, grid);
    const double df = fs / static_cast<double>(nfft);
    const auto k0 = static_cast<std::size_t>(std::ceil(opt.min_vibration_hz / df));
    const auto k1 = std::min(spec.size() - 2, static_cast<std::size_t>(0.45 * fs / df));
    if (k0 + 4 >= k1) return peak;
    std::vector<double> mag(k1 - k0 + 1);
    std::size_t best = k0;
    for (std::size_t k = k0; k <= k1; ++k) {
        mag[k - k0] = std::abs(spec[k]);
        if (mag[k - k0] > std::abs(spec[best])) best = k;
    }
    std::vector<double> sorted = mag;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
    const double median = sorted[sorted.size() / 2];
    const double scale = 2.0 / static_cast<double>(in.points.size());
    const double a = std::abs(spec[best - 1]), b = std::abs(spec[best]), c = std::abs(spec[best + 1]);
    const double denom = a - 2.0 * b + c;
    const double shift = denom != 0.0 ? std::clamp(0.5 * (a - c) / denom, -0.5, 0.5) : 0.0;
    peak.k = (static_cast<double>(best) + shift) * df;
    peak.amp = b * scale;
    peak.found = b > 10.0 * median && peak.amp > 0.1;
    peak.strength = peak.amp / std::sqrt(2.0);
    return peak;
}

double amplitude_std(const Solution& s, int i, int j) {
    const double a = s.beta[i], b = s.beta[j];
    const double c = std::hypot(a, b);
    if (c <= 0.0) return std::sqrt(0.5 * (s.cov(i, i) + s.cov(j, j)));
    const double var = (a * a * s.cov(i, i) + b * b * s.cov(j, j) + 2.0 * a * b * s.cov(i, j)) / (c * c);
    return std::sqrt(std::max(var, 0.0));
}

}  // namespace

FitOutput fit_diagnostics(const FitInput& in, const AnalysisOptions& opt) {
    FitOutput out;
    if (in.points.size() < 50) throw CircularError("too few samples in the data arcs to diagnose (need 50)");
    const Model model(in);
    State st;
    // The mean lag of the axes from the runs' feed-ins (each feed-in moves along its start angle).
    auto update_tau_mean = [&] {
        double sum = 0.0;
        for (std::size_t k = 0; k < in.run_lag_s.size(); ++k)
            sum += in.run_lag_s[k] - 0.5e-3 * st.dtau_ms * std::cos(2.0 * in.run_start_rad[k]);
        st.tau_mean_s = std::max(sum / static_cast<double>(std::max<std::size_t>(in.run_lag_s.size(), 1)), 0.0);
    };
    update_tau_mean();

    std::vector<int> base;
    for (int c = 0; c < kBaseCount; ++c) base.push_back(c);
    // Separability judged without the lag: a reversal that only the lag moves into the data arc
    // (a few samples) must not count as information.
    Design d;
    model.build(State{}, base, d);
    const Separability sep = check_separability(d, in, opt);
    out.unseparable = sep.groups;
    std::vector<int> ids = sep.accepted;
    const bool servo = std::find(ids.begin(), ids.end(), kServo) != ids.end();

    Solution sol;
    Normal ne;
    auto after_solve = [&] {
        const int sv = d.col(kServo);
        if (sv >= 0) st.dtau_ms = sol.beta[sv];
        update_tau_mean();
    };
    // A fit from scratch: the design and the data linearised about the lag of `st`.
    auto run_fit = [&](const std::vector<int>& cols) {
        model.build(st, cols, d);
        normal_full(d, ne);
        solve(d, ne, sol);
        after_solve();
    };
    // A fit of the design with columns appended (the searches' terms): the columns it has and the data
    // stay linearised where they were; the lag is taken up again by the Gauss–Newton steps below.
    auto run_fit_appended = [&](const std::vector<int>& cols) {
        const Eigen::Index from = d.used;
        model.build(st, cols, d, static_cast<std::size_t>(from));
        normal_append(d, from, ne);
        solve(d, ne, sol);
        after_solve();
    };
    run_fit(ids);

    // Cyclic errors and vibration, the strongest first, each searched on what the others left.
    Eigen::FFT<double> fft;
    fft.SetFlag(Eigen::FFT<double>::HalfSpectrum);
    bool want_p = true, want_q = true, want_v = true;
    while (want_p || want_q || want_v) {
        Peak best;
        int which = -1;
        const Peak cands[3] = {want_p ? search_cyclic(in, model, st, sol.residual, 0, opt) : Peak{},
                               want_q ? search_cyclic(in, model, st, sol.residual, 1, opt) : Peak{},
                               want_v ? search_vibration(in, sol.residual, opt, fft) : Peak{}};
        for (int c = 0; c < 3; ++c)
            if (cands[c].found && cands[c].strength > best.strength) best = cands[c], which = c;
        if (which < 0) break;
        if (which == 0) st.kp = best.k, want_p = false, ids.insert(ids.end(), {kCycPs, kCycPc});
        if (which == 1) st.kq = best.k, want_q = false, ids.insert(ids.end(), {kCycQs, kCycQc});
        if (which == 2) st.f_hz = best.k, want_v = false, ids.insert(ids.end(), {kVibS, kVibC});
        run_fit_appended(ids);
    }
    // Gauss–Newton on pitches and frequency (and the lag) together with everything linear.
    std::vector<int> gn = ids;
    if (st.kp > 0.0) gn.push_back(kDkP);
    if (st.kq > 0.0) gn.push_back(kDkQ);
    if (st.f_hz > 0.0) gn.push_back(kDf);
    const double dk = 1.0 / (10.0 * model.radius());
    const double fspan = 1.0 / std::max(2.0 * std::abs(in.points.back().t - model.t_mid()), 1e-3);
    // The last solve is the result: derivative columns included, so pitch and frequency carry
    // uncertainties (their step there is the last correction, not applied). The first step's design
    // is the searches' with the derivative columns appended; the last is rebuilt whole where the
    // steps and the lag have brought the state.
    const int iterations = gn.size() > ids.size() ? 2 : servo ? 1 : 0;
    for (int it = 0; it < iterations; ++it) {
        auto take = [&](int s, int c, double& as, double& ac) {
            if (d.col(s) >= 0) as = sol.beta[d.col(s)], ac = sol.beta[d.col(c)];
        };
        take(kCycPs, kCycPc, st.ap_s, st.ap_c);
        take(kCycQs, kCycQc, st.aq_s, st.aq_c);
        take(kVibS, kVibC, st.av_s, st.av_c);
        if (it + 1 < iterations)
            run_fit_appended(gn);
        else
            run_fit(gn);
        if (it + 1 == iterations) break;
        if (d.col(kDkP) >= 0) st.kp += std::clamp(sol.beta[d.col(kDkP)], -dk, dk);
        if (d.col(kDkQ) >= 0) st.kq += std::clamp(sol.beta[d.col(kDkQ)], -dk, dk);
        if (d.col(kDf) >= 0) st.f_hz += std::clamp(sol.beta[d.col(kDf)], -fspan, fspan);
    }

    out.residual_rms_um = sol.rms;
    out.mean_radius_um = sol.beta[d.col(kConst)];
    out.mean_radius_std_um = std::sqrt(sol.cov(d.col(kConst), d.col(kConst)));
    out.lag_mean_s = st.tau_mean_s;
    out.fitted_um.resize(in.points.size());
    for (std::size_t i = 0; i < in.points.size(); ++i) {
        const auto row = static_cast<Eigen::Index>(i);
        double vibration = 0.0;
        for (int c : {kVibS, kVibC, kDf})
            if (d.col(c) >= 0) vibration += d.x()(row, d.col(c)) * sol.beta[d.col(c)];
        out.fitted_um[i] = in.points[i].y_um - sol.residual[row] - vibration;
    }

    // Peak to valley of the terms' part of the fit, over the data. One column: its value times a
    // constant, and rounding a product is monotonic in the column, so the extremes are the column's
    // (swapped for a negative constant) — the same numbers as evaluating every row.
    auto contribution = [&](std::initializer_list<int> cols) {
        std::vector<int> at;  // the design's columns of these terms, looked up once
        for (int c : cols)
            if (d.col(c) >= 0) at.push_back(d.col(c));
        if (at.empty() || d.x().rows() == 0) return 0.0;
        if (at.size() == 1) {
            const auto col = d.x().col(at[0]);
            const double b = sol.beta[at[0]];
            const double hi = col.maxCoeff() * b, lo = col.minCoeff() * b;
            return b >= 0.0 ? hi - lo : lo - hi;
        }
        double lo = 0.0, hi = 0.0;
        for (Eigen::Index i = 0; i < d.x().rows(); ++i) {
            double v = 0.0;
            for (int c : at) v += d.x()(i, c) * sol.beta[c];
            lo = i == 0 ? v : std::min(lo, v), hi = i == 0 ? v : std::max(hi, v);
        }
        return hi - lo;
    };
    auto is_confounded = [&](int id) {
        return std::find(sep.confounded.begin(), sep.confounded.end(), id) != sep.confounded.end();
    };
    for (int id : sep.accepted) {
        const auto diag = col_diag(id);
        if (!diag) continue;
        const int c = d.col(id);
        if (is_confounded(id)) {
            for (auto& g : out.unseparable)
                if (g.combined_key == diagnostic_key(*diag, in.test.plane))
                    g.combined_value = sol.beta[c], g.combined_std = std::sqrt(sol.cov(c, c));
            continue;
        }
        DiagnosticResult r;
        r.diag = *diag;
        r.key = diagnostic_key(*diag, in.test.plane);
        r.value = sol.beta[c];
        r.std_uncertainty = std::sqrt(sol.cov(c, c));
        r.contribution_um = contribution({id});
        out.diagnostics.push_back(r);
    }
    auto periodic = [&](Diag amp, Diag period, int cs, int cc, int dcol, double k, bool frequency) {
        DiagnosticResult r;
        r.diag = amp;
        r.key = diagnostic_key(amp, in.test.plane);
        if (d.col(cs) < 0) {
            r.detected = false;
            r.std_uncertainty = 0.0;
            out.diagnostics.push_back(r);
            return;
        }
        r.value = std::hypot(sol.beta[d.col(cs)], sol.beta[d.col(cc)]);
        r.std_uncertainty = amplitude_std(sol, d.col(cs), d.col(cc));
        r.contribution_um = contribution({cs, cc});
        out.diagnostics.push_back(r);
        DiagnosticResult p;
        p.diag = period;
        p.key = diagnostic_key(period, in.test.plane);
        const double sk = d.col(dcol) >= 0 ? std::sqrt(sol.cov(d.col(dcol), d.col(dcol))) : 0.0;
        p.value = frequency ? k : 1.0 / k;
        p.std_uncertainty = frequency ? sk : sk / (k * k);
        out.diagnostics.push_back(p);
    };
    periodic(Diag::CyclicP, Diag::CyclicPitchP, kCycPs, kCycPc, kDkP, st.kp, false);
    periodic(Diag::CyclicQ, Diag::CyclicPitchQ, kCycQs, kCycQc, kDkQ, st.kq, false);
    periodic(Diag::Vibration, Diag::VibrationHz, kVibS, kVibC, kDf, st.f_hz, true);

    double total = 0.0;
    for (const auto& r : out.diagnostics) total += r.contribution_um;
    if (total > 0.0)
        for (auto& r : out.diagnostics) r.share_percent = 100.0 * r.contribution_um / total;
    return out;
}

}  // namespace ballbar::analysis::circular::detail
