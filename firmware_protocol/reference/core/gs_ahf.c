/* See gs_ahf.h. Each line mirrors groundstation/estimation/ahf.py (ahf_kernel) and
 * groundstation/estimation/base.py (screen, guard); keep them in step. */
#include "gs_ahf.h"

#include <math.h>
#include <stddef.h>

/* x^-0.5 (the normalisations of seed 000 eq. 9, 18 and 19) and x^0.5 (the gate) in float from the
 * operations IEEE 754 rounds correctly (division and sqrtf), as the ground station's float32 model writes
 * them (1.0 / np.sqrt(x), np.sqrt(x)): every C library and FPU, the board's newlib and soft float among
 * them, computes them alike, so the board, the host build and the model agree bit for bit. Not powf: C libraries round it differently (newlib's differs from glibc's in
 * 9 % of inputs), and the filter turns one ulp into degrees (docs/firmware.md). */
static float rsqrt(float x) { return 1.0f / sqrtf(x); }
static float root(float x) { return sqrtf(x); }

void gs_ahf_default_settings(gs_ahf_settings *s)
{
    s->lambda_max = 2.0;
    s->lambda_min = 0.2;
    s->lowpass = 0.9;
    s->error_gain = 10.0;
    s->gyro_overrange_rad_s = HUGE_VAL;
    s->acc_min_g = 0.2;
    s->acc_deviation_max_g = HUGE_VAL;
    s->acc_window_s = 1.0;
    s->max_gap_s = 1.0;
}

/* Quaternion (yaw, then pitch and roll from gravity), in double as quaternion.from_euler_zyx. */
static void set_from_gravity(gs_ahf *f, float ax, float ay, float az, double yaw_rad)
{
    double x = ax, y = ay, z = az;
    double pitch = atan2(x, sqrt(y * y + z * z)), roll = atan2(-y, -z);
    double hy = yaw_rad / 2.0, hp = pitch / 2.0, hr = roll / 2.0;
    double cy = cos(hy), sy = sin(hy), cp = cos(hp), sp = sin(hp), cr = cos(hr), sr = sin(hr);
    f->q[0] = (float)(cy * cp * cr + sy * sp * sr);
    f->q[1] = (float)(cy * cp * sr - sy * sp * cr);
    f->q[2] = (float)(cy * sp * cr + sy * cp * sr);
    f->q[3] = (float)(sy * cp * cr - cy * sp * sr);
}

int gs_ahf_init(gs_ahf *f, const gs_ahf_settings *s, const float *q0)
{
    if (!(0.0 <= s->lambda_min && s->lambda_min <= s->lambda_max)) return -1;
    if (!(0.0 <= s->acc_min_g && s->acc_min_g < 1.0) || !(s->acc_deviation_max_g > 0.0) || !(s->acc_window_s > 0.0)) return -1;
    if (!(s->max_gap_s > 0.0)) return -1; /* any dt would re-initialise: the filter would never integrate */
    f->settings = *s;
    f->lam_max = (float)s->lambda_max;
    f->lam_min = (float)s->lambda_min;
    f->lowpass = (float)s->lowpass;
    f->gain = (float)((1.0 - s->lowpass) * s->error_gain);
    f->overrange = (float)s->gyro_overrange_rad_s;
    f->overrange_on = s->gyro_overrange_rad_s != HUGE_VAL;
    f->acc_min2 = (float)(s->acc_min_g * s->acc_min_g);
    f->acc_dev_max = (float)s->acc_deviation_max_g;
    f->acc_gated = s->acc_deviation_max_g != HUGE_VAL;
    f->acc_window_s = (float)s->acc_window_s;
    f->acc_dev = 0.0f;
    f->dt_run = 0.0f;
    f->max_gap_s = (float)s->max_gap_s;
    f->e_a = 0.0f;
    f->lam = f->lam_max;
    f->err = 0.0f;
    if (q0 == NULL) {
        f->q[0] = 1.0f;
        f->q[1] = f->q[2] = f->q[3] = 0.0f;
        f->waiting = 1;
    } else {
        double w = q0[0], x = q0[1], y = q0[2], z = q0[3];
        double norm = sqrt(w * w + x * x + y * y + z * z);
        if (!(norm > 0.0)) return -1;
        f->q[0] = (float)(w / norm);
        f->q[1] = (float)(x / norm);
        f->q[2] = (float)(y / norm);
        f->q[3] = (float)(z / norm);
        f->waiting = 0;
    }
    return 0;
}

unsigned gs_ahf_step(gs_ahf *f, const float gyr_rad_s[3], const float acc_g[3], float dt_s)
{
    float gx = gyr_rad_s[0], gy = gyr_rad_s[1], gz = gyr_rad_s[2];
    float ax = acc_g[0], ay = acc_g[1], az = acc_g[2];
    float n2 = ax * ax + ay * ay + az * az;
    /* NaN fails every comparison, so this one test rejects NaN, Inf and free fall. */
    int acc_ok = f->acc_min2 <= n2 && n2 < INFINITY;
    /* Only a finite positive dt weighs the deviation: inf would make it inf/inf = NaN for good. */
    if (acc_ok && f->acc_gated && dt_s > 0.0f && dt_s < INFINITY) {
        /* Sustained shaking or acceleration: the deviation from 1 g, low-passed over acc_window_s */
        float dev = f->acc_dev;
        dev = dev + (fabsf(root(n2) - 1.0f) - dev) * dt_s / (f->acc_window_s + dt_s);
        f->acc_dev = dev;
        acc_ok = dev <= f->acc_dev_max;
    }
    unsigned status = 0;
    if (f->waiting) {
        if (!acc_ok) return GS_AHF_WAITING;
        set_from_gravity(f, ax, ay, az, 0.0);
        f->waiting = 0;
        status = GS_AHF_INITIALISED;
    }
    float total = gx + gy + gz + dt_s;
    if (!(dt_s > 0.0f) || total - total != 0.0f) return status | GS_AHF_HELD;
    if (dt_s > f->max_gap_s) {
        if (!acc_ok) return status | GS_AHF_HELD;
        double w = f->q[0], x = f->q[1], y = f->q[2], z = f->q[3];
        set_from_gravity(f, ax, ay, az, atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)));
        return status | GS_AHF_REINITIALISED;
    }
    if (!acc_ok) status |= GS_AHF_ACC_SKIPPED;
    /* The interval rule: at most GS_AHF_STEP_RATIO_MAX running intervals in one step */
    if (f->dt_run == 0.0f) f->dt_run = dt_s;
    float limit_s = GS_AHF_STEP_RATIO_MAX * f->dt_run;
    if (dt_s > limit_s) {
        dt_s = limit_s;
        status |= GS_AHF_LIMITED;
    }
    f->dt_run = f->dt_run + (dt_s - f->dt_run) * GS_AHF_INTERVAL_WEIGHT;

    float q1 = f->q[0], q2 = f->q[1], q3 = f->q[2], q4 = f->q[3];
    /* (eq. 6) q_dot_w = 1/2 q x [0, w] */
    float d1 = 0.5f * (-q2 * gx - q3 * gy - q4 * gz);
    float d2 = 0.5f * (q1 * gx + q3 * gz - q4 * gy);
    float d3 = 0.5f * (q1 * gy - q2 * gz + q4 * gx);
    float d4 = 0.5f * (q1 * gz + q2 * gy - q3 * gx);
    if (acc_ok) {
        /* a: the measured down direction, -acc normalised */
        float r = -rsqrt(ax * ax + ay * ay + az * az);
        ax = ax * r;
        ay = ay * r;
        az = az * r;
        /* (eq. 8) g: the estimated down direction in the body frame */
        float vx = 2.0f * (q2 * q4 - q1 * q3);
        float vy = 2.0f * (q1 * q2 + q3 * q4);
        float vz = q1 * q1 - q2 * q2 - q3 * q3 + q4 * q4;
        /* (eq. 9) f = g - a */
        float fx = vx - ax, fy = vy - ay, fz = vz - az;
        /* (eq. 10, 12) grad f = J^T f */
        float s1 = -2.0f * q3 * fx + 2.0f * q2 * fy;
        float s2 = 2.0f * q4 * fx + 2.0f * q1 * fy - 4.0f * q2 * fz;
        float s3 = -2.0f * q1 * fx + 2.0f * q4 * fy - 4.0f * q3 * fz;
        float s4 = 2.0f * q2 * fx + 2.0f * q3 * fy;
        /* Tangent projection grad f <- grad f - (q . grad f) q: the step no longer depends on the mounting
         * (estimation/ahf.py's module docstring) */
        float p = q1 * s1 + q2 * s2 + q3 * s3 + q4 * s4;
        s1 = s1 - p * q1;
        s2 = s2 - p * q2;
        s3 = s3 - p * q3;
        s4 = s4 - p * q4;
        /* (eq. 20) e = g x a; e_a low-passed; lambda = clamp(lambda_max - e_a) */
        float err = fabsf(vy * az - vz * ay) + fabsf(vz * ax - vx * az) + fabsf(vx * ay - vy * ax);
        float lam = f->lam_max;
        float e_a = f->lowpass * f->e_a + f->gain * err;
        f->e_a = e_a;
        lam = lam - e_a;
        if (lam < f->lam_min) {
            lam = f->lam_min;
        } else if (lam > f->lam_max) {
            lam = f->lam_max;
        }
        if (f->overrange_on && (fabsf(gx) >= f->overrange || fabsf(gy) >= f->overrange || fabsf(gz) >= f->overrange)) {
            lam = f->lam_max;
            status |= GS_AHF_GYRO_OVERRANGE;
        }
        f->lam = lam;
        f->err = err;
        float g2 = s1 * s1 + s2 * s2 + s3 * s3 + s4 * s4;
        if (g2 > 0.0f) {
            /* (eq. 18) q_dot = q_dot_w - lambda grad f / |grad f| */
            float k = lam * rsqrt(g2);
            d1 = d1 - k * s1;
            d2 = d2 - k * s2;
            d3 = d3 - k * s3;
            d4 = d4 - k * s4;
        }
    }
    /* (eq. 19) q(k) = q(k-1) + q_dot dt, normalised */
    q1 = q1 + d1 * dt_s;
    q2 = q2 + d2 * dt_s;
    q3 = q3 + d3 * dt_s;
    q4 = q4 + d4 * dt_s;
    float r = rsqrt(q1 * q1 + q2 * q2 + q3 * q3 + q4 * q4);
    f->q[0] = q1 * r;
    f->q[1] = q2 * r;
    f->q[2] = q3 * r;
    f->q[3] = q4 * r;
    return status;
}
