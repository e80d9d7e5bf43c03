/*
 * A C controller on toolconf's model library of the Franka Emika Panda: one control tick of the
 * active-inference controller, as libfranka's or ros2_control's 1 kHz loop would make it.
 *
 * Built against the header and library `make model` writes (examples/c_controller/Makefile):
 *
 *     make model IR=generated/panda.json OUT=/tmp/panda        # or DESC=derive/models/panda.toml
 *     make -C examples/c_controller LIB=/tmp/panda run
 *
 * The tool is the Franka Hand at the flange; the task is the Panda's position task with the
 * model's own goals and precisions; gamma = 1, U0 = 0.1 N m on every joint, 1000 Hz. The measured
 * state is the equilibrium, joint i 0.01 (i+1) rad off it and moving at 0.05 (i-3) rad/s. It
 * prints the torque for the next millisecond and the tool's control confidence ln|Pi^U|, then the
 * same numbers as their bits, which `make c-example-test` compares with the Rust controller's
 * (examples/on_robot/tests/panda_tick.rs): they must be the same bits.
 *
 * In a real loop, toolconf_controller_create is called once before the loop (it allocates) and
 * toolconf_controller_tick once per period (it does not allocate); a failed tick (a NaN from an
 * encoder) is a status, and the controller keeps the torque it had.
 */
#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "toolconf_model.h"

/* The Franka Hand at the flange, as `toolconf tool --urdf ... --flange panda_link8` gives it
 * (docs/how-to/tool-from-urdf.md), in the order of TOOLCONF_PARAMETER_*. */
static const double FRANKA_HAND[TOOLCONF_PARAMETER_COUNT] = {
    0.76,
    -0.006791946714028682,
    0.006791946714028679,
    0.03112105263157894,
    0.001803432452631579,
    0.0018034324526315793,
    0.0017523815789473685,
    0.0007274407894736841,
    -5.786738600352437e-6,
    5.7867386003524354e-6,
    0.0,
    0.0,
    0.1034,
};

/* Nonzero (and a line on stderr) unless `status` is TOOLCONF_OK. */
static int failed(int32_t status, const char *what) {
    if (status == TOOLCONF_OK) {
        return 0;
    }
    fprintf(stderr, "c_controller: %s: %s: %s\n", what, toolconf_status_name(status), toolconf_last_error());
    return 1;
}

static void print_bits(const char *name, const double *values, size_t count) {
    for (size_t i = 0; i < count; i++) {
        uint64_t b;
        memcpy(&b, &values[i], sizeof b);
        printf("bits %s[%zu] 0x%016" PRIx64 "\n", name, i, b);
    }
}

int main(void) {
    /* The library must be the one this program was compiled for. */
    if (toolconf_abi_version() != TOOLCONF_ABI_VERSION) {
        fprintf(stderr, "c_controller: the library's C ABI is version %" PRIu32 ", this program's %u\n",
                toolconf_abi_version(), TOOLCONF_ABI_VERSION);
        return 1;
    }
    if (strcmp(toolconf_tasks_fingerprint(), TOOLCONF_TASKS_FINGERPRINT) != 0) {
        fprintf(stderr, "c_controller: the library was derived with other tasks than this program's header\n");
        return 1;
    }
    const toolconf_metadata *info = toolconf_model_info();
    if (info == NULL || strcmp(info->name, TOOLCONF_MODEL_NAME) != 0 || info->dof != TOOLCONF_DOF ||
        info->parameter_count != TOOLCONF_PARAMETER_COUNT) {
        fprintf(stderr, "c_controller: the library is not the model %s this program was compiled for\n",
                TOOLCONF_MODEL_NAME);
        return 1;
    }
    if (failed(toolconf_check_tool(FRANKA_HAND), "toolconf_check_tool")) {
        return 1;
    }

    /* The task: the model's own goals and precisions of its position task. */
    double goals[TOOLCONF_TERM_COUNT * TOOLCONF_DOF];
    double precisions[TOOLCONF_TERM_COUNT * TOOLCONF_DOF * TOOLCONF_DOF];
    if (failed(toolconf_task_defaults(TOOLCONF_TASK_POSITION, goals, precisions), "toolconf_task_defaults")) {
        return 1;
    }

    /* Once, before the loop: the controller (gamma = 1, U0 = 0.1 N m, 1 kHz). */
    double initial_torque[TOOLCONF_DOF];
    for (size_t i = 0; i < TOOLCONF_DOF; i++) {
        initial_torque[i] = 0.1;
    }
    toolconf_controller *controller = NULL;
    if (failed(toolconf_controller_create(FRANKA_HAND, TOOLCONF_TASK_POSITION, goals, precisions, 1.0,
                                          initial_torque, 1000.0, &controller),
               "toolconf_controller_create")) {
        return 1;
    }

    /* Each millisecond: the measured state X = [q; q_dot] in, the torque out. */
    double state[TOOLCONF_STATE_DIM];
    for (size_t i = 0; i < TOOLCONF_DOF; i++) {
        state[i] = info->equilibrium_state[i] + 0.01 * (double)(i + 1);
        state[TOOLCONF_DOF + i] = 0.05 * ((double)i - 3.0);
    }
    double torque[TOOLCONF_DOF];
    double confidence;
    if (failed(toolconf_controller_tick(controller, state, torque, &confidence), "toolconf_controller_tick")) {
        toolconf_controller_destroy(controller);
        return 1;
    }
    printf("c: one tick of the %s controller (task position, 1000 Hz), through %s's C ABI %u\n",
           TOOLCONF_MODEL_NAME, info->name, TOOLCONF_ABI_VERSION);
    for (size_t i = 0; i < TOOLCONF_DOF; i++) {
        printf("torque[%zu] = %.17g N m\n", i, torque[i]);
    }
    printf("confidence ln|Pi^U| = %.17g\n", confidence);

    /* A measurement that is not a number is a status, and the controller keeps its torque. */
    double broken[TOOLCONF_STATE_DIM];
    memcpy(broken, state, sizeof broken);
    broken[0] = NAN;
    double ignored[TOOLCONF_DOF];
    double ignored_confidence;
    int32_t status = toolconf_controller_tick(controller, broken, ignored, &ignored_confidence);
    printf("a NaN measurement: %s (%s)\n", toolconf_status_name(status), toolconf_last_error());
    if (status != TOOLCONF_NOT_FINITE || toolconf_controller_destroy(controller) != TOOLCONF_OK) {
        return 1;
    }
    /* The handle is checked: ticking or destroying it again is a status, not freed memory. */
    int32_t again = toolconf_controller_tick(controller, state, ignored, &ignored_confidence);
    printf("a tick after destroy: %s\n", toolconf_status_name(again));
    int32_t twice = toolconf_controller_destroy(controller);
    printf("a second destroy: %s\n", toolconf_status_name(twice));
    if (again != TOOLCONF_BAD_HANDLE || twice != TOOLCONF_BAD_HANDLE) {
        return 1;
    }

    print_bits("params", FRANKA_HAND, TOOLCONF_PARAMETER_COUNT);
    print_bits("state", state, TOOLCONF_STATE_DIM);
    print_bits("torque", torque, TOOLCONF_DOF);
    print_bits("confidence", &confidence, 1);
    return 0;
}
