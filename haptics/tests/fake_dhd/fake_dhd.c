/* A stand-in for Force Dimension's libdhd: the same C symbols and prototypes (dhdc.h), with
 * canned device readings and a record of what was commanded, so the loader, the calling
 * convention and the error paths can be tested without the SDK or a device.
 * Built by haptics/tests/it/omega7_loader.rs with the system C compiler. */

#include <string.h>

static int device_count = 1;
static int open_result = 0;
static int fail_position_after = -1;
static int position_calls = 0;
static int forces_enabled = -1;
static int closed = 0;
static double last_force[8];
static const char *last_error = "no error";
static int watchdog_steps = -1;

int dhdGetDeviceCount(void) { return device_count; }

int dhdOpen(void) {
    if (open_result < 0) {
        last_error = "fake: no device found";
    }
    return open_result;
}

int dhdClose(char id) {
    (void)id;
    closed = 1;
    return 0;
}

int dhdGetPosition(double *px, double *py, double *pz, char id) {
    if (id != 0) return -1;
    if (fail_position_after >= 0 && position_calls >= fail_position_after) {
        last_error = "fake: communication error";
        return -1;
    }
    position_calls++;
    *px = 0.01;
    *py = -0.02;
    *pz = 0.03;
    return 0;
}

#ifndef OMIT_VELOCITY
int dhdGetLinearVelocity(double *vx, double *vy, double *vz, char id) {
    (void)id;
    *vx = 0.1;
    *vy = 0.2;
    *vz = 0.3;
    return 0;
}
#endif

int dhdGetGripperGap(double *g, char id) {
    (void)id;
    *g = 0.015;
    return 0;
}

int dhdSetForceAndTorqueAndGripperForce(double fx, double fy, double fz, double tx, double ty, double tz,
                                        double fg, char id) {
    last_force[0] = fx;
    last_force[1] = fy;
    last_force[2] = fz;
    last_force[3] = tx;
    last_force[4] = ty;
    last_force[5] = tz;
    last_force[6] = fg;
    last_force[7] = (double)id;
    return 0;
}

int dhdEnableForce(unsigned char val, char id) {
    (void)id;
    forces_enabled = val;
    return 0;
}

void dhdGetSDKVersion(int *major, int *minor, int *release, int *revision) {
    *major = 3;
    *minor = 17;
    *release = 6;
    *revision = 42;
}

int dhdGetButtonMask(char id) {
    (void)id;
    return 1;
}

double dhdGetTime(void) { return 1234.5; }

const char *dhdErrorGetLastStr(void) { return last_error; }

#ifndef OMIT_WATCHDOG
int dhdSetWatchdog(unsigned char val, char id) {
    (void)id;
    watchdog_steps = val;
    return 0;
}
#endif

const char *dhdGetSystemName(char id) {
    (void)id;
    return "omega.7 (fake)";
}

/* Test controls. */
void fakeSetDeviceCount(int n) { device_count = n; }
void fakeSetOpenResult(int r) { open_result = r; }
void fakeFailPositionAfter(int n) { fail_position_after = n; position_calls = 0; }
int fakeForcesEnabled(void) { return forces_enabled; }
int fakeClosed(void) { return closed; }
void fakeLastForce(double *out) { memcpy(out, last_force, sizeof last_force); }
int fakeWatchdog(void) { return watchdog_steps; }
