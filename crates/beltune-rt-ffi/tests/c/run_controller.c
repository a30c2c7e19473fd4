/* Runs the exported controller (controller.h from `beltune export --lang c`)
 * through the C ABI of libbeltune_rt_ffi.a on a planned move: prints the move
 * duration, then one torque per line ("%.17g", exact round trip) for the
 * measured motor angles read from the file given as argument (one per line).
 * Used by tests/c_program.rs, which runs the same in Rust and compares. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "beltune_rt.h"
#include "controller.h"

static BtCascade ctrl;
static BtCascade never_initialized;
static BtTrajectory traj;
static BtSetpointConversion conv;

static int motor_sample(double t_s, BtMotionSample *out) {
    BtCartSample cart;
    if (bt_trajectory_sample(&traj, t_s, &cart) != BT_OK) return 1;
    return bt_setpoint_convert(&conv, &cart, out) != BT_OK;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: %s MEASURED_ANGLES\n", argv[0]);
        return 2;
    }
    /* the ABI refuses what it cannot run */
    BtSetpoint hold = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    if (bt_cascade_reset_to(&never_initialized, 0.0) != BT_ERR_UNINITIALIZED ||
        bt_cascade_step(&never_initialized, &hold, 0.0, NULL) != 0.0 ||
        bt_cascade_init(NULL, &BELTUNE_CASCADE) != BT_ERR_NULL) {
        fprintf(stderr, "uninitialized or null objects were not refused\n");
        return 1;
    }
    BtCascadeConfig broken = BELTUNE_CASCADE;
    broken.torque_max_nm = -1.0;
    if (bt_cascade_init(&ctrl, &broken) != BT_ERR_INVALID) {
        fprintf(stderr, "a negative torque limit was accepted\n");
        return 1;
    }
    if (bt_cascade_init(&ctrl, &BELTUNE_CASCADE) != BT_OK ||
        bt_setpoint_init(&conv, &BELTUNE_SETPOINT) != BT_OK) {
        fprintf(stderr, "init failed\n");
        return 1;
    }
    BtState start = {0.05, 0.0, 0.0};
    BtState target = {0.55, 0.0, 0.0};
    BtLimits limits = {2.0, -2.0, 20.0, -20.0, 400.0, -400.0, -INFINITY, INFINITY};
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
    BtMotionSample first;
    if (motor_sample(0.0, &first)) return 1;
    bt_cascade_reset_to(&ctrl, first.angle_rad);
    double measured;
    for (unsigned long k = 0; fscanf(f, "%lf", &measured) == 1; k++) {
        double t = (double)k * BELTUNE_TS_S;
        BtSetpoint sp;
        if (motor_sample(t, &sp.now) ||
            motor_sample(t + (double)BELTUNE_PREVIEW_SAMPLES * BELTUNE_TS_S, &sp.ahead)) {
            return 1;
        }
        BtControlOutput out;
        double torque = bt_cascade_step(&ctrl, &sp, measured, &out);
        if (torque != out.torque_nm || !out.finite) return 1;
        printf("%.17g\n", torque);
    }
    fclose(f);
    return 0;
}
