// SPDX-License-Identifier: MIT
// The closed-form reading model against the templated kinematics: the same reading to 1e-12 mm, and
// the gradient equal to forward-mode AutoDiff of predicted_reading<AutoDiffScalar> for every
// parameter and the socket position, on all three types with every error parameter non-zero.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <random>
#include <unsupported/Eigen/AutoDiff>

#include "ballbar/analysis/kinematics.hpp"
#include "ballbar/analysis/reading_model.hpp"

namespace ba = ballbar::analysis;

namespace {

constexpr int kDer = static_cast<int>(ba::kParamCount) + 3;
using Der = Eigen::Matrix<double, kDer, 1>;
using AD = Eigen::AutoDiffScalar<Der>;

ba::MachineGeometry geometry(ba::MachineType type) {
    ba::MachineGeometry g;
    g.type = type;
    g.a_pivot_mm = ba::Vec3(3, -40, 120);
    g.c_offset_mm = ba::Vec3(0.5, 1, -95);
    g.tool_ball_mm = ba::Vec3(0.2, -0.1, -150);
    return g;
}

// Every parameter at a size ten to a hundred times what a real machine shows, so that no term of
// the gradient is hidden by a small factor.
ba::ErrorParams all_errors(std::mt19937_64& rng) {
    std::uniform_real_distribution<double> u(-1, 1);
    ba::ErrorParams e;
    for (std::size_t k = 0; k < ba::kParamCount; ++k) {
        const auto p = static_cast<ba::Param>(k);
        double scale = 0.5;  // mm
        switch (ba::param_info(p).unit) {
            case ba::ParamUnit::rad:
                scale = 5e-3;
                break;
            case ba::ParamUnit::mm_per_mm:
                scale = 1e-3;
                break;
            case ba::ParamUnit::mm_per_h:
                scale = 0.2;
                break;
            case ba::ParamUnit::per_K:
                scale = 5e-5;
                break;
            case ba::ParamUnit::mm:
                break;
        }
        e.values[k] = scale * u(rng);
    }
    return e;
}

}  // namespace

TEST(ReadingModel, MatchesTheKinematicsAndTheirAutoDiffGradient) {
    std::mt19937_64 rng(20261121);
    std::uniform_real_distribution<double> lin(-150, 150), ang(-3.0, 3.0), temp(15, 30), time(0, 7200);
    for (auto type : {ba::MachineType::TTTRR, ba::MachineType::RRTTT, ba::MachineType::RTTTR}) {
        const ba::MachineGeometry g = geometry(type);
        for (int machine = 0; machine < 5; ++machine) {
            const ba::ErrorParams e = all_errors(rng);
            const ba::ReadingModel model(g, e);
            ba::ErrorParamsT<AD> ead;
            for (std::size_t k = 0; k < ba::kParamCount; ++k) {
                ead.values[k] = AD(e.values[k], Der::Zero());
                ead.values[k].derivatives()[static_cast<Eigen::Index>(k)] = 1.0;
            }
            for (int i = 0; i < 40; ++i) {
                ba::Pose pose{lin(rng), lin(rng), lin(rng), ang(rng), ang(rng), ang(rng)};
                const ba::Vec3 socket(lin(rng) / 3, lin(rng) / 3, lin(rng) / 10);
                const ba::ReadingConditions cond{time(rng), temp(rng)};
                ba::ReadingModel::Gradient grad;
                const double value = model.predict(pose, socket, cond, &grad);
                EXPECT_NEAR(value, ba::predicted_reading(g, e, pose, socket, cond), 1e-12);
                EXPECT_EQ(model.predict(pose, socket, cond), value);

                ba::Vec3T<AD> sad;
                for (int a = 0; a < 3; ++a) {
                    sad[a] = AD(socket[a], Der::Zero());
                    sad[a].derivatives()[static_cast<Eigen::Index>(ba::kParamCount) + a] = 1.0;
                }
                const AD ref = ba::predicted_reading<AD>(g, ead, pose, sad, cond);
                for (std::size_t k = 0; k < ba::kParamCount; ++k) {
                    const double want = ref.derivatives()[static_cast<Eigen::Index>(k)];
                    EXPECT_NEAR(grad.params[k], want, 1e-9 * (1.0 + std::abs(want)))
                        << ba::to_string(type) << " " << ba::param_info(static_cast<ba::Param>(k)).name;
                }
                for (int a = 0; a < 3; ++a)
                    EXPECT_NEAR(grad.socket_mm[a], ref.derivatives()[static_cast<Eigen::Index>(ba::kParamCount) + a],
                                1e-12)
                        << ba::to_string(type) << " socket " << a;
            }
        }
    }
}
