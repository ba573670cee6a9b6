/* The adaptive hybrid filter of seed 000 (eq. 6-20) in single precision: the onboard estimate.
 *
 * The same constants and order of operations as groundstation/estimation/ahf.py run with
 * dtype=np.float32 (and the input guards of groundstation/estimation/base.py), so the two agree bit
 * for bit: every update is float arithmetic in the order the Python writes it, only with the operations
 * IEEE 754 rounds correctly (+, -, *, /, sqrtf: x^-0.5 is 1.0f / sqrtf(x), as the Python's 1.0 / np.sqrt(x)),
 * so any C library computes the same bits (newlib on the STM32: tests/firmware/test_fw_cross.py), and the
 * few steps the Python does in double (initialisation from gravity, re-normalising a given attitude, the
 * settings) are done in double here too (their atan2, sin and cos, within an ulp in any C library, change
 * the float they are rounded to only when that lands within an ulp of double of a rounding boundary, about
 * once in 2^28). Build without -ffast-math and without FMA contraction (-ffp-contract=off), or the last
 * bits differ.
 *
 * Frames: q = (w, x, y, z) rotates body (forward-right-down) vectors into north-east-down; gyro in
 * rad/s and accelerometer in g on the body axes (docs/conventions.md). */
#ifndef GS_AHF_H
#define GS_AHF_H

/* Status bits, as groundstation/estimation/base.py numbers them. */
#define GS_AHF_WAITING 1u        /* no usable accelerometer sample yet: output is the identity */
#define GS_AHF_INITIALISED 2u    /* attitude set from the accelerometer on this sample */
#define GS_AHF_HELD 4u           /* bad gyro or dt: previous estimate unchanged */
#define GS_AHF_ACC_SKIPPED 8u    /* accelerometer unusable (NaN/Inf, free fall, sustained deviation): gyro only */
#define GS_AHF_REINITIALISED 16u /* dt > max_gap_s: pitch and roll re-set from the accelerometer */
#define GS_AHF_GYRO_OVERRANGE 32u /* a gyro axis at or above gyro_overrange_rad_s: lambda = lambda_max */
#define GS_AHF_LIMITED 64u       /* dt above GS_AHF_STEP_RATIO_MAX running intervals: integrated as that many */

/* The interval rule (estimation/base.py, STEP_RATIO_MAX and INTERVAL_WEIGHT) */
#define GS_AHF_STEP_RATIO_MAX 1.5f
#define GS_AHF_INTERVAL_WEIGHT 0.25f

typedef struct {
    double lambda_max;            /* rad/s, 2.0 (eq. 20) */
    double lambda_min;            /* rad/s, 0.2 (eq. 20) */
    double lowpass;               /* weight of e_a(k-1), 0.9 (eq. 20) */
    double error_gain;            /* scale of |ex|+|ey|+|ez|, 10 (eq. 20) */
    double gyro_overrange_rad_s;  /* any |w_i| >= this forces lambda_max; HUGE_VAL = off */
    double acc_min_g;             /* accelerometer norm below: free fall, skipped; 0.2 g */
    double acc_deviation_max_g;   /* low-passed |norm - 1 g| above: skipped; HUGE_VAL = off (the default) */
    double acc_window_s;          /* time constant of that low-pass, 1 s */
    double max_gap_s;             /* longer dt: re-initialise from gravity, 1 s */
} gs_ahf_settings;

typedef struct {
    gs_ahf_settings settings;
    float lam_max, lam_min, lowpass, gain, overrange, acc_min2, acc_dev_max, acc_window_s, max_gap_s;
    int overrange_on, acc_gated;
    int waiting;   /* no attitude yet: the next usable accelerometer sample sets it */
    float q[4];    /* the estimate, w first */
    float lam;     /* lambda used on the last sample, rad/s */
    float e_a;     /* low-passed, scaled gravity error (eq. 20) */
    float err;     /* |ex| + |ey| + |ez| of the last sample (eq. 20) */
    float acc_dev; /* low-passed |norm of acc - 1| (g), updated only while the gate is on */
    float dt_run;  /* the running sample interval, s (the interval rule); 0 before the first */
} gs_ahf;

/* The paper's settings (the defaults of AhfSettings). */
void gs_ahf_default_settings(gs_ahf_settings *s);

/* Starts the filter with settings s; q0 (w, x, y, z, any norm) starts from that attitude, NULL waits
 * for gravity. Returns 0, or -1 (filter untouched) when the settings are invalid. */
int gs_ahf_init(gs_ahf *f, const gs_ahf_settings *s, const float *q0);

/* One sample: updates f->q, f->lam, f->e_a, f->err; returns the status bits. */
unsigned gs_ahf_step(gs_ahf *f, const float gyr_rad_s[3], const float acc_g[3], float dt_s);

#endif /* GS_AHF_H */
