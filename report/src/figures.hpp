// SPDX-License-Identifier: MIT
// The report's figures: each reserves its space on the current page (or the next) and draws there.
#pragma once

#include <vector>

#include "ballbar/report/report.hpp"
#include "document.hpp"

namespace ballbar::report {

void figure_trace(Document& doc, const Report& r);
void figure_vectors(Document& doc, const Report& r);
void figure_orientation(Document& doc, const Report& r);
void figure_discovery(Document& doc, const std::vector<DiscoveryStep>& steps);
void figure_compensation(Document& doc, const Report& r);

}  // namespace ballbar::report
