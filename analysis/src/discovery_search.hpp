// SPDX-License-Identifier: MIT
// The search beyond the library (docs/discovery.md, "Beyond the library"): which variable, and which
// shape in it, explains the structure the library leaves. Private to the discovery workflow.
#pragma once

#include <Eigen/Core>
#include <span>
#include <string>
#include <vector>

#include "ballbar/analysis/discovery.hpp"
#include "ballbar/analysis/empirical.hpp"

namespace ballbar::analysis::detail {

struct SearchInput {
    const ReadingSet& readings;
    const Eigen::MatrixXd& model_jac;   ///< unit-norm columns of the current model (parameters, sockets, learned terms)
    const Eigen::MatrixXd& model_gram;  ///< their Gram matrix
    const Eigen::VectorXd& residual_mm;
    const TermBasis& basis;
    const std::vector<EmpiricalFamily>& families;
    std::span<const LearnedTerm> learned;  ///< already in the model: not searched again
    double alpha = 0.01;
    double min_independence = 0.02;
};

struct SearchOutput {
    bool found = false;
    double score = 0;                       ///< the winning family's ΔRSS/σ² − Σ thresholds
    double delta_rss_mm2 = 0, penalty = 0;  ///< its ΔRSS and Σ thresholds (in units of σ²)
    EmpiricalStep step;                     ///< terms with their estimates, the family table, the test
    std::vector<Eigen::VectorXd> columns;   ///< raw Jacobian columns of step.terms
    std::vector<std::string> not_searchable;
};

SearchOutput search_beyond_library(const SearchInput& in);

/// The residual seen as the quantity of the step's main term (an angle error, a positioning error, …)
/// in bins of its variable; `unit` gets that quantity's display unit, the bin centres are in the
/// variable's display unit (degrees, mm, min, °C).
VariableTrend term_trend(const ReadingSet& readings, const TermBasis& basis, const EmpiricalTerm& main,
                         const Eigen::VectorXd& residual_mm, std::string* unit, std::string* label);

/// "the C axis: once per revolution, 78 µrad, phase 40°", from the learned terms of one family.
std::string describe(const std::string& family, std::span<const LearnedTerm> terms);

}  // namespace ballbar::analysis::detail
