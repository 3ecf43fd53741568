// SPDX-License-Identifier: MIT
// The discovery workflow (docs/discovery.md): fit the current model to the readings (through
// identify.hpp's fit_error_model), look at where the residuals disagree, test every candidate effect
// of the library with a linearised score test around the current fit, add the one that passes the
// criterion best, refit, and repeat until no candidate passes.
//
// Criterion: a nested-model F-test of one added parameter, Bonferroni-corrected over the candidates of
// the step so that a step with no real effect names one with probability `family_alpha` at most.
// Confounding: a candidate whose Jacobian column lies (nearly) in the span of the model's columns is
// unidentifiable with these readings; candidates whose columns (after the model is projected out)
// are nearly parallel are reported together as confounded.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ballbar/analysis/effects.hpp"
#include "ballbar/analysis/empirical.hpp"
#include "ballbar/analysis/identify.hpp"
#include "ballbar/analysis/reading.hpp"

namespace ballbar::analysis {

struct DiscoveryOptions {
    /// The model to start from; empty: the base model (rotary_params_for(type)).
    std::vector<Param> base_model;
    /// Probability that one step names an effect when the readings hold none (family-wise, over all
    /// candidates of the step).
    double family_alpha = 0.01;
    /// A candidate whose column keeps less than this fraction of its norm once the model's columns are
    /// projected out cannot be told apart from the model (sqrt(1 − R²)).
    double min_independence = 0.02;
    /// Two candidates whose projected columns have |cos| above this are confounded with each other.
    double confound_cos = 0.98;
    int max_steps = 12;
    /// Largest number of effects one explanation (subset search) may hold.
    int max_subset = 3;

    /// The measurement noise of one reading (mm), when the user knows it; otherwise it is estimated
    /// from the readings (estimate_noise_floor).
    std::optional<double> noise_mm;
    /// The instrument's resolution (mm), when known: the estimated floor is never below resolution/√12
    /// (its quantisation), so nothing below what the instrument can tell apart is called structure.
    std::optional<double> resolution_mm;
    /// The residual is unexplained structure when P(χ² ≥ observed) under the noise floor is below this.
    double noise_alpha = 0.001;
    /// Family-wise false-alarm rate of one search beyond the library (Bonferroni over its groups of
    /// terms); with an unknown noise floor `search_alpha_unknown_floor` applies instead.
    double search_alpha = 0.01;
    double search_alpha_unknown_floor = 0.001;
    /// Largest number of empirical families learned.
    int max_learned = 3;
};

/// Per-reading variables residuals are analysed against. Columns: time_s, bar_temp_C, X_mm, Y_mm,
/// Z_mm, first rotary (rad), second rotary (rad), bar direction u_x, u_y, u_z (nominal, machine frame).
Eigen::MatrixXd explaining_variables(const ReadingSet& readings);

/// How well one variable explains a residual series: R² of the directional trend
/// r ≈ v·(c0 + c·u) (for `bar_direction`: r ≈ c0 + c·u), and the binned trend of r against v.
struct VariableTrend {
    ExplainingVariable variable;
    double r2 = 0;                                           ///< 0..1, fraction of the residual's sum of squares
    std::vector<double> bin_centre, bin_mean_mm, bin_count;  ///< 8 quantile bins (empty for bar_direction)
};

struct ResidualAnalysis {
    Eigen::VectorXd residual_mm;  ///< measured − predicted per reading
    double rms_mm = 0;
    std::array<VariableTrend, kExplainingVariableCount> trends;
    ExplainingVariable best = ExplainingVariable::bar_direction;  ///< highest r2
};

/// Analyses `residual_mm` against `variables` (from explaining_variables()).
ResidualAnalysis analyse_residuals(const Eigen::VectorXd& residual_mm, const Eigen::MatrixXd& variables);
/// The same for one variable.
VariableTrend residual_trend(const Eigen::VectorXd& residual_mm, const Eigen::MatrixXd& variables,
                             ExplainingVariable v);

/// The measurement noise of one reading, and where it comes from.
struct NoiseFloor {
    double sigma_mm = 0;  ///< 0: unknown
    std::string source;   ///< "given", "within-point spread", "repeated points", "unknown"
    std::string detail;   ///< e.g. "252 readings, n = 40 samples each"
    /// The data's floor was below the instrument's resolution/√12 and was raised to it: a residual
    /// below it is nothing the instrument can show, and the library adds no effect to explain it.
    bool raised_to_resolution = false;
    bool known() const { return sigma_mm > 0; }
};

/// The floor from (in this order) the user's figure, the readings' own within-point spread
/// (σ² = mean of std_mm²/n over the readings that give it, at least half of them), or the spread of
/// the residuals `residual_mm` of repeated points (same socket and pose; at least 10 degrees of freedom).
NoiseFloor estimate_noise_floor(const ReadingSet& readings, const Eigen::VectorXd& residual_mm,
                                std::optional<double> user_mm, std::optional<double> resolution_mm = std::nullopt);

/// Is the residual consistent with the noise floor? χ² = Σr²/σ², dof = readings − fitted unknowns,
/// p = P(χ²(dof) ≥ χ²); unexplained structure when p < alpha.
struct NoiseVerdict {
    bool floor_known = false;
    double rms_mm = 0, ratio = 0;  ///< RMS and RMS / floor
    double chi2 = 0, dof = 0, p_value = 1, alpha = 0.001;
    bool structure = false;  ///< true: unexplained structure (never reported as noise)
    std::string text;        ///< "consistent with noise", "unexplained structure", "noise floor unknown"
};
NoiseVerdict noise_verdict(const Eigen::VectorXd& residual_mm, double fitted_unknowns, const NoiseFloor& floor,
                           double alpha);

/// One family's result in a search beyond the library.
struct FamilyScore {
    std::string family, variable;
    std::vector<std::string> terms;  ///< the terms its forward selection kept
    double delta_rss_mm2 = 0;        ///< drop of the residual sum of squares with them
    double f = 0, p_value = 1;       ///< nested-model F-test of them against the model: (dof1, dof2)
    double dof1 = 0, dof2 = 0;
    double score = 0;  ///< ΔRSS/σ² − Σ thresholds: positive when it beats the model
    bool passes = false;
};

/// A term learned beyond the library: where the structure lives and what it is.
struct EmpiricalStep {
    std::string family;              ///< "C_angular"
    std::string variable;            ///< "C"
    std::string description;         ///< "the C axis: once per revolution, 78 µrad, phase 40°"
    std::vector<LearnedTerm> terms;  ///< as the final model has them
    double rms_before_mm = 0, rms_after_mm = 0;
    double f = 0, p_value = 1, dof1 = 0, dof2 = 0, threshold_p = 0;
    /// The residual seen as the term's own quantity (an angle error, a positioning error, …) in bins of
    /// its variable, before and after the step; `trend_unit` is that quantity's unit.
    VariableTrend trend_before, trend_after;
    std::string trend_unit, trend_label;
    std::vector<FamilyScore> families;  ///< every family of the search, best first
};

/// One candidate's score in one step.
struct CandidateScore {
    const Effect* effect = nullptr;
    double independence = 0;   ///< sqrt(1 − R²) of its column against the model's
    double delta_rss_mm2 = 0;  ///< linearised drop of the residual sum of squares
    double f = 0;              ///< F statistic (1, n − p − 1)
    double p_value = 1;
    bool passes = false;
};

struct DiscoveryStep {
    const Effect* effect = nullptr;
    double estimate = 0;             ///< in the effect's unit, as the final model has it
    double estimate_when_added = 0;  ///< as the refit of its step had it
    double std_error = 0;            ///< its standard uncertainty
    double rms_before_mm = 0, rms_after_mm = 0;
    std::string criterion;  ///< "F"
    double value = 0;       ///< F statistic of the refitted model against the previous one
    double p_value = 1;
    ExplainingVariable explained_by = ExplainingVariable::bar_direction;
    /// The residuals against `explained_by`, before and after this step (what the report draws).
    VariableTrend trend_before, trend_after;
    std::vector<CandidateScore> candidates;  ///< every candidate of the step, best first
    ErrorParams model_after{};               ///< the model's parameters after the step's refit
    /// Taken out again: once a learned term explained the structure, its F-test given the rest of the
    /// model no longer passed (Bonferroni over the library effects in the model).
    bool withdrawn = false;
};

struct DiscoveryResult {
    MachineType type = MachineType::TTTRR;
    std::vector<Param> base_model;   ///< the base model as fitted (unobservable ones left out)
    std::vector<Param> final_model;  ///< base model plus the steps' parameters
    double rms_initial_mm = 0;       ///< after fitting the base model
    ErrorParams base_fit{};          ///< the base model's parameters as fitted
    double rms_final_mm = 0;
    std::vector<DiscoveryStep> steps;
    /// Groups of names the data cannot tell apart (effect ids, parameter names, "socket<k>.z").
    std::vector<std::vector<std::string>> confounded;
    /// Parameters and effects the readings cannot determine (names as in `confounded`).
    std::vector<std::string> unidentifiable;
    std::string criterion_text;  ///< e.g. "F-test, family-wise false-alarm rate 0.01 (Bonferroni over 10)"
    FitSummary final_fit;
    ResidualAnalysis initial_residuals, final_residuals;
    Eigen::MatrixXd variables;  ///< explaining_variables() of the readings (rows as the residuals)

    NoiseFloor noise_floor;
    NoiseVerdict verdict_library;  ///< after the library steps, before any empirical term
    NoiseVerdict verdict;          ///< of the final residual
    std::vector<EmpiricalStep> learned;
    std::vector<LearnedTerm> learned_terms;  ///< every learned term with its final value
    /// Empirical terms the readings cannot tell from the model (not searched).
    std::vector<std::string> not_searchable;
    /// What the search concluded when the residual is above the floor and nothing located it.
    std::string unlocated;
};

/// The workflow. Throws AnalysisError for readings it cannot fit (too few, inconsistent machine).
DiscoveryResult discover(const ReadingSet& readings, const DiscoveryOptions& options = {});

/// Upper tail of the F distribution, P(F(d1, d2) > f), through the regularized incomplete beta function.
double f_distribution_sf(double f, double d1, double d2);
/// Upper tail of the F distribution inverted: the f with P(F(d1, d2) > f) = alpha.
double f_critical(double alpha, double d1, double d2);
/// Upper tail of the χ² distribution, P(χ²(dof) > x), through the regularized incomplete gamma function.
double chi_square_sf(double x, double dof);
/// Regularized incomplete beta function I_x(a, b).
double incomplete_beta(double a, double b, double x);

}  // namespace ballbar::analysis
