/* Runs the single-precision export (controller.h from `beltune export --lang c
 * --precision f32`) through the float ABI of libbeltune_rt_ffi.a over the
 * validation move (thesis chapter 5: 0 -> 0.5 m, limits of Table A.8): the
 * move is planned in double (bt_trajectory_plan) and sampled into float
 * (bt_trajectory_sample_f32), converted by bt_setpoint_f32_convert and fed to
 * bt_cascade_f32_step. Reads lines "t_now_s t_ahead_s measured_angle_rad"
 * (times as double, the angle as float) from the file given as argument and
 * prints the move duration, then one torque per line ("%.9g": a float reads
 * back exactly). Used by tests/exported_f32.rs. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "beltune_rt.h"
#include "controller.h"

static BtCascadeF32 ctrl;
static BtCascadeF32 never_initialized;
static BtTrajectory traj;
static BtSetpointConversionF32 conv;

static int motor_sample(double t_s, BtMotionSampleF32 *out) {
    BtCartSampleF32 cart;
    if (bt_trajectory_sample_f32(&traj, t_s, &cart) != BT_OK) return 1;
    return bt_setpoint_f32_convert(&conv, &cart, out) != BT_OK;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: %s SAMPLES\n", argv[0]);
        return 2;
    }
    /* the ABI refuses what it cannot run */
    BtSetpointF32 hold = {{0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}};
    if (bt_cascade_f32_reset_to(&never_initialized, 0.0f) != BT_ERR_UNINITIALIZED ||
        bt_cascade_f32_step(&never_initialized, &hold, 0.0f, NULL) != 0.0f ||
        !isnan(bt_cascade_f32_integrator_rad(&never_initialized)) ||
        bt_cascade_f32_init(NULL, &BELTUNE_CASCADE) != BT_ERR_NULL) {
        fprintf(stderr, "uninitialized or null objects were not refused\n");
        return 1;
    }
    BtCascadeConfigF32 broken = BELTUNE_CASCADE;
    broken.torque_max_nm = -1.0f;
    if (bt_cascade_f32_init(&ctrl, &broken) != BT_ERR_INVALID) {
        fprintf(stderr, "a negative torque limit was accepted\n");
        return 1;
    }
    BtSetpointConfigF32 no_stiffness = BELTUNE_SETPOINT;
    no_stiffness.belt_stretch = true;
    no_stiffness.c_n_per_m = 0.0f;
    if (bt_setpoint_f32_init(&conv, &no_stiffness) != BT_ERR_INVALID) {
        fprintf(stderr, "a belt without stiffness was accepted\n");
        return 1;
    }
    if (bt_cascade_f32_init(&ctrl, &BELTUNE_CASCADE) != BT_OK ||
        bt_setpoint_f32_init(&conv, &BELTUNE_SETPOINT) != BT_OK) {
        fprintf(stderr, "init failed\n");
        return 1;
    }
    BtState start = {0.0, 0.0, 0.0};
    BtState target = {0.5, 0.0, 0.0};
    BtLimits limits = {5.0, -5.0, 45.0, -45.0, 40.0, -40.0, -0.01, 0.57};
    if (bt_trajectory_plan(&traj, &start, &target, &limits) != BT_OK) {
        fprintf(stderr, "no trajectory\n");
        return 1;
    }
    printf("%.17g\n", bt_trajectory_duration_s(&traj));

    FILE *f = fopen(argv[1], "r");
    if (!f) {
        perror(argv[1]);
        return 1;
    }
    double t_now, t_ahead;
    float measured;
    for (unsigned long k = 0; fscanf(f, "%lf %lf %f", &t_now, &t_ahead, &measured) == 3; k++) {
        /* bumpless start at the motor's angle before the move */
        if (k == 0 && bt_cascade_f32_reset_to(&ctrl, measured) != BT_OK) return 1;
        BtSetpointF32 sp;
        if (motor_sample(t_now, &sp.now) || motor_sample(t_ahead, &sp.ahead)) return 1;
        BtControlOutputF32 out;
        float torque = bt_cascade_f32_step(&ctrl, &sp, measured, &out);
        if (torque != out.torque_nm || !out.finite) return 1;
        printf("%.9g\n", (double)torque);
    }
    fclose(f);
    return 0;
}
