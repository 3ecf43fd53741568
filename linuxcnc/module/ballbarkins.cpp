// SPDX-License-Identifier: MIT
// ballbarkins: LinuxCNC kinematics module for table-tilting XYZAC machines that adds the first-order
// correction of an identified `ballbar-model/1` in every servo cycle (docs/linuxcnc.md).
//
//   loadrt ballbarkins model=FILE [sparm=identityfirst]     ([KINS]KINEMATICS, JOINTS = 5, XYZAC)
//
// Switchable as LinuxCNC's xyzac-trt-kins: type 0 is the tool-centre-point kinematics and type 1
// identity (joint mode), swapped by sparm=identityfirst; both add the correction. The mathematics
// is CompensatingKins (linuxcnc/src/kins.cpp) over the library's Compensator: this file only binds
// it to LinuxCNC's kinematics interface and HAL. The model is read once, at load; the servo-cycle
// path allocates nothing, locks nothing and does no I/O.
//
// LinuxCNC's headers are GPL; LinuxCNC's modules declare MODULE_LICENSE("GPL") and so does this one
// (its own code is MIT, compatible with it).
#include <cerrno>
#include <cmath>
#include <exception>
#include <new>

#include "ballbar/linuxcnc/kins.hpp"

// hal.h and rtapi.h declare C linkage themselves; emcpos.h (posemath) has C++ overloads of its own;
// kinematics.h declares the functions this file defines without saying their linkage: C, as motmod
// calls them.
#include "emcpos.h"
#include "hal.h"
#include "rtapi.h"
#include "rtapi_app.h"
extern "C" {
#include "kinematics.h"
}

namespace {

using ballbar::linuxcnc::Axes;
using ballbar::linuxcnc::CompensatingKins;
using ballbar::linuxcnc::KinsType;

struct Pins {
    hal_bit_t* enable;           // in: the correction on (default) or off (nominal kinematics)
    hal_float_t* tool_offset;    // in: the tool-length offset (motion.tooloffset.z)
    hal_float_t* correction[5];  // out: the last inverse's correction, mm and degrees
    hal_float_t* max_linear;     // out: the largest |linear correction| applied (mm)
    hal_float_t* max_rotary;     // out: the largest |rotary correction| applied (degrees)
    hal_u32_t* singular_count;   // out: inverse calls with a rotary axis not corrected
    hal_u32_t* model_hash;       // out: FNV-1a of the model file
    hal_bit_t* is_tcp;           // out: the tool-centre-point type is in force
};

Pins* pins = nullptr;
int comp_id = -1;
int switchkins_type = 0;
bool identity_first = false;
// Built at load (rtapi_app_main), read-only in the servo cycle.
alignas(CompensatingKins) unsigned char kins_storage[sizeof(CompensatingKins)];
CompensatingKins* kins = nullptr;

KinsType current_type() {
    const bool tcp = (switchkins_type == 0) != identity_first;
    return tcp ? KinsType::tcp : KinsType::identity;
}

Axes axes_of(const EmcPose& p) {
    return {p.tran.x, p.tran.y, p.tran.z, p.a, p.c};
}

}  // namespace

extern "C" {

static char* model = nullptr;
RTAPI_MP_STRING(model, "the ballbar-model/1 file (TTTRR) whose correction is applied");
static char* sparm = nullptr;
RTAPI_MP_STRING(sparm, "identityfirst: type 0 is identity, type 1 the tool-centre point");
// LinuxCNC passes coordinates= to switchable kinematics; ballbarkins is fixed to XYZAC on joints 0-4.
static char* coordinates = nullptr;
RTAPI_MP_STRING(coordinates, "must be XYZAC (the default)");

MODULE_LICENSE("GPL");
MODULE_DESCRIPTION("ballbar: XYZAC table-tilting kinematics with an identified error model's correction");

int kinematicsInverse(const EmcPose* world, double* joints, const KINEMATICS_INVERSE_FLAGS*,
                      KINEMATICS_FORWARD_FLAGS*) {
    const bool enable = *pins->enable;
    const auto r = kins->inverse(current_type(), axes_of(*world), *pins->tool_offset, enable);
    for (int i = 0; i < 5; ++i) {
        joints[i] = r.joints[static_cast<std::size_t>(i)];
        *pins->correction[i] = r.correction[static_cast<std::size_t>(i)];
    }
    const double lin = std::sqrt(r.correction[0] * r.correction[0] + r.correction[1] * r.correction[1] +
                                 r.correction[2] * r.correction[2]);
    const double rot = std::fmax(std::fabs(r.correction[3]), std::fabs(r.correction[4]));
    if (lin > *pins->max_linear) *pins->max_linear = lin;
    if (rot > *pins->max_rotary) *pins->max_rotary = rot;
    if (enable && r.singular) *pins->singular_count = *pins->singular_count + 1;
    return 0;
}

int kinematicsForward(const double* joints, EmcPose* world, const KINEMATICS_FORWARD_FLAGS*,
                      KINEMATICS_INVERSE_FLAGS*) {
    const Axes j{joints[0], joints[1], joints[2], joints[3], joints[4]};
    const Axes w = kins->forward(current_type(), j, *pins->tool_offset, *pins->enable);
    world->tran.x = w[0];
    world->tran.y = w[1];
    world->tran.z = w[2];
    world->a = w[3];
    world->c = w[4];
    world->b = world->u = world->v = world->w = 0;
    return 0;
}

KINEMATICS_TYPE kinematicsType(void) {
    return KINEMATICS_BOTH;
}

int kinematicsSwitchable(void) {
    return 1;
}

int kinematicsSwitch(int new_type) {
    if (new_type != 0 && new_type != 1) {
        rtapi_print_msg(RTAPI_MSG_ERR, "ballbarkins: kinematics type %d does not exist (0 and 1 do)\n", new_type);
        return -1;
    }
    switchkins_type = new_type;
    *pins->is_tcp = current_type() == KinsType::tcp;
    return 0;
}

EXPORT_SYMBOL(kinematicsType);
EXPORT_SYMBOL(kinematicsForward);
EXPORT_SYMBOL(kinematicsInverse);
EXPORT_SYMBOL(kinematicsSwitchable);
EXPORT_SYMBOL(kinematicsSwitch);

int rtapi_app_main(void) {
    if (!model || !model[0]) {
        rtapi_print_msg(RTAPI_MSG_ERR, "ballbarkins: no model: loadrt ballbarkins model=FILE (a ballbar-model/1)\n");
        return -EINVAL;
    }
    if (coordinates && coordinates[0] && std::string_view(coordinates) != "XYZAC" &&
        std::string_view(coordinates) != "xyzac") {
        rtapi_print_msg(RTAPI_MSG_ERR, "ballbarkins: coordinates=%s: only XYZAC (joints 0-4) is supported\n",
                        coordinates);
        return -EINVAL;
    }
    identity_first = sparm && std::string_view(sparm).find("identityfirst") != std::string_view::npos;
    try {
        kins = new (kins_storage) CompensatingKins(CompensatingKins::from_model_file(model));
    } catch (const std::exception& e) {
        rtapi_print_msg(RTAPI_MSG_ERR, "ballbarkins: %s\n", e.what());
        return -EINVAL;
    }
    comp_id = hal_init("ballbarkins");
    if (comp_id < 0) return comp_id;
    pins = static_cast<Pins*>(hal_malloc(sizeof(Pins)));
    if (!pins) {
        hal_exit(comp_id);
        return -ENOMEM;
    }
    int r = 0;
    r |= hal_pin_bit_newf(HAL_IN, &pins->enable, comp_id, "ballbarkins.enable");
    r |= hal_pin_float_newf(HAL_IN, &pins->tool_offset, comp_id, "ballbarkins.tool-offset");
    static const char* const names[5] = {"x", "y", "z", "a", "c"};
    for (int i = 0; i < 5; ++i)
        r |= hal_pin_float_newf(HAL_OUT, &pins->correction[i], comp_id, "ballbarkins.correction-%s", names[i]);
    r |= hal_pin_float_newf(HAL_OUT, &pins->max_linear, comp_id, "ballbarkins.max-correction-linear");
    r |= hal_pin_float_newf(HAL_OUT, &pins->max_rotary, comp_id, "ballbarkins.max-correction-rotary");
    r |= hal_pin_u32_newf(HAL_OUT, &pins->singular_count, comp_id, "ballbarkins.singular-count");
    r |= hal_pin_u32_newf(HAL_OUT, &pins->model_hash, comp_id, "ballbarkins.model-hash");
    r |= hal_pin_bit_newf(HAL_OUT, &pins->is_tcp, comp_id, "ballbarkins.is-tcp");
    if (r) {
        rtapi_print_msg(RTAPI_MSG_ERR, "ballbarkins: cannot create its HAL pins\n");
        hal_exit(comp_id);
        return -EINVAL;
    }
    *pins->enable = 1;
    *pins->model_hash = kins->model_hash();
    *pins->is_tcp = current_type() == KinsType::tcp;
    const auto eq = kins->xyzac_equivalent();
    rtapi_print(
        "ballbarkins: model %s (FNV-1a %08x) loaded; type 0 is %s; nominal twin: xyzac-trt-kins x-rot-point %.6f "
        "y-rot-point %.6f z-rot-point %.6f y-offset %.6f z-offset %.6f\n",
        model, static_cast<unsigned>(kins->model_hash()), identity_first ? "identity" : "the tool-centre point",
        eq.x_rot_point, eq.y_rot_point, eq.z_rot_point, eq.y_offset, eq.z_offset);
    hal_ready(comp_id);
    return 0;
}

void rtapi_app_exit(void) {
    if (kins) {
        kins->~CompensatingKins();
        kins = nullptr;
    }
    hal_exit(comp_id);
}

}  // extern "C"
