// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "ballbar/report/decimate.hpp"

namespace ballbar::report {
namespace {

std::vector<double> ramp(std::size_t n) {
    std::vector<double> x(n);
    for (std::size_t i = 0; i < n; ++i) x[i] = static_cast<double>(i);
    return x;
}

TEST(Decimate, KeepsEveryColumnsExtremesAndTheGlobalOnes) {
    const std::size_t n = 100000, columns = 100;
    std::mt19937 rng(3);
    std::normal_distribution<double> noise(0, 1);
    const auto x = ramp(n);
    std::vector<double> y(n);
    for (auto& v : y) v = noise(rng);
    y[31337] = 50;   // a spike that a stride-based thinning would almost surely miss
    y[77777] = -42;  // and a dip
    const XYSeries d = decimate_minmax(x, y, 0, static_cast<double>(n), columns);
    EXPECT_LE(d.x.size(), 4 * columns);
    EXPECT_EQ(*std::max_element(d.y.begin(), d.y.end()), 50);
    EXPECT_EQ(*std::min_element(d.y.begin(), d.y.end()), -42);
    // Per column, the kept points hold that column's min and max exactly.
    const double width = static_cast<double>(n) / columns;
    for (std::size_t c = 0; c < columns; ++c) {
        const auto lo = static_cast<std::size_t>(static_cast<double>(c) * width);
        const auto hi = static_cast<std::size_t>(static_cast<double>(c + 1) * width);
        const double mn = *std::min_element(y.begin() + lo, y.begin() + hi);
        const double mx = *std::max_element(y.begin() + lo, y.begin() + hi);
        double kmn = 1e300, kmx = -1e300;
        for (std::size_t i = 0; i < d.x.size(); ++i)
            if (d.x[i] >= static_cast<double>(lo) && d.x[i] < static_cast<double>(hi))
                kmn = std::min(kmn, d.y[i]), kmx = std::max(kmx, d.y[i]);
        ASSERT_EQ(kmn, mn) << "column " << c;
        ASSERT_EQ(kmx, mx) << "column " << c;
    }
}

TEST(Decimate, KeepsOrderAndFirstAndLastPoints) {
    const auto x = ramp(10000);
    std::vector<double> y(x.size());
    for (std::size_t i = 0; i < y.size(); ++i) y[i] = std::sin(static_cast<double>(i) * 0.01);
    const XYSeries d = decimate_minmax(x, y, 0, 10000, 50);
    EXPECT_TRUE(std::is_sorted(d.x.begin(), d.x.end()));
    EXPECT_EQ(std::adjacent_find(d.x.begin(), d.x.end()), d.x.end()) << "a sample kept twice";
    EXPECT_EQ(d.x.front(), 0);
    EXPECT_EQ(d.x.back(), 9999);
    EXPECT_EQ(d.y.back(), y.back());
}

TEST(Decimate, ShortSeriesAreReturnedUnchanged) {
    const std::vector<double> x{0, 1, 2, 3, 4}, y{5, -1, 7, 2, 0};
    const XYSeries d = decimate_minmax(x, y, 0, 4, 2);
    EXPECT_EQ(d.x, x);
    EXPECT_EQ(d.y, y);
}

TEST(Decimate, StreamingEqualsBatch) {
    const auto x = ramp(5000);
    std::vector<double> y(x.size());
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(-1, 1);
    for (auto& v : y) v = u(rng);
    const XYSeries batch = decimate_minmax(x, y, 0, 5000, 64);
    MinMaxDecimator stream(0, 5000, 64);
    for (std::size_t i = 0; i < x.size(); ++i) stream.add(x[i], y[i]);
    EXPECT_EQ(stream.seen(), x.size());
    const XYSeries s = stream.take();
    EXPECT_EQ(s.x, batch.x);
    EXPECT_EQ(s.y, batch.y);
}

TEST(Decimate, RefusesBadInput) {
    const std::vector<double> x{0, 1, 2}, y{0, 1};
    EXPECT_THROW(decimate_minmax(x, y, 0, 2, 10), std::invalid_argument);
    std::vector<double> xs = ramp(100), ys(100, 0.0);
    std::swap(xs[10], xs[50]);
    EXPECT_THROW(decimate_minmax(xs, ys, 0, 100, 2), std::invalid_argument);
    EXPECT_THROW(MinMaxDecimator(0, 1, 0), std::invalid_argument);
    EXPECT_THROW(MinMaxDecimator(1, 0, 10), std::invalid_argument);
}

TEST(Decimate, PointsFarOutsideTheRangeGoToTheEdgeColumns) {
    MinMaxDecimator d(0, 10, 5);
    d.add(-1e300, 1);
    d.add(5, 2);
    d.add(1e300, 3);
    const XYSeries s = d.take();
    EXPECT_EQ(s.y, (std::vector<double>{1, 2, 3}));
}

}  // namespace
}  // namespace ballbar::report
