/* The DNBS step of pa10_dnbs/core/dnbs_controller.py (DNBSControllers.answer and .learn) in C, with the
 * same result bits as the numpy reference.
 *
 * Why the bits agree:
 * - every sum over weights (w^T H, P H, H^T P H) reproduces numpy's add.reduce of a contiguous row:
 *   pairwise_sum of numpy/_core/src/umath/loops_utils.h.src, started from the identity +0.0 (psum);
 * - every other operation is the same IEEE-754 operation in the same order as the numpy expression,
 *   built with -ffp-contract=off (no fused multiply-add) and without -ffast-math;
 * - tanh is not computed here: the caller applies numpy's np.tanh to the buffers tanh_in and tanh_alpha
 *   between the three answer calls (libm's tanh and numpy's SIMD tanh differ in the last bits).
 * test/test_compiled_dnbs.py checks the agreement bit for bit.
 *
 * Memory: the kernel reads and writes the numpy arrays whose addresses it is given (w, P, H, last_hph,
 * alpha, torque_unsaturated) in place; its own scratch is allocated here and freed by dnbs_free.
 * Rows: n joints; the EKF bank has 2n rows (alpha networks 0..n-1, torque networks n..2n-1) of width W. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define INLINE static inline __attribute__((always_inline))

/* numpy's pairwise sum of a[0..n-1], n <= 128 (without the reduce's starting +0.0): fewer than 8 numbers
 * one after the other, else 8 interleaved partial sums added as a tree, then the rest one by one */
INLINE double psum_block(const double *a, long n) {
    if (n < 8) {
        double res = 0.0;
        for (long i = 0; i < n; i++) res += a[i];
        return res;
    }
    double r[8];
    long i;
    for (int j = 0; j < 8; j++) r[j] = a[j];
    for (i = 8; i < n - (n % 8); i += 8)
        for (int j = 0; j < 8; j++) r[j] += a[i + j];
    double res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for (; i < n; i++) res += a[i];
    return res;
}

/* numpy's pairwise sum of any length: more than 128 numbers are split in halves (a multiple of 8 first) */
static double psum(const double *a, long n) {
    if (n <= 128) return psum_block(a, n);
    long n2 = n / 2;
    n2 -= n2 % 8;
    return psum(a, n2) + psum(a + n2, n - n2);
}

/* np.add.reduce(row) of a contiguous row: the identity +0.0, then the pairwise sum */
INLINE double reduce_row(const double *a, long n) { return 0.0 + (n <= 128 ? psum_block(a, n) : psum(a, n)); }

/* np.maximum / np.minimum of two doubles: NaN in either propagates, and on a tie the second operand, as numpy
   gives it (np.maximum(-0.0, 0.0) is +0.0: a weight clipped to a bound of 0 is +0.0 in both) */
INLINE double np_max(double a, double b) { return (a > b || isnan(a)) ? a : b; }
INLINE double np_min(double a, double b) { return (a < b || isnan(a)) ? a : b; }

/* What the Python side fills in (pa10_dnbs/accel/compiled_dnbs.py, class _Config: same fields, same order). */
typedef struct {
    long n, W;                      /* joints; padded width of the EKF bank's rows */
    long La, Lt, Da, Dt;            /* terms and factors per term of the alpha and the torque network */
    long oa, ot;                    /* column offset of each network in its padded row */
    const long *fa, *ft;            /* HONN factor tables (L, D): indices into ext = [1, tanh inputs...] */
    double *w, *P, *H, *hph;        /* the bank's w (2n, W), P (2n, W, W), regressors H (2n, W), last_hph (2n) */
    double *alpha, *u_unsat;        /* the controller's alpha (n) and torque_unsaturated (n) */
    const double *ia, *it;          /* 1 / input_scale of the two networks (2 and 3) */
    const double *A, *U, *ka, *ku;  /* output scales and robust-term gains (n) */
    const double *lim;              /* the joints' torque limits (n), N m */
    const double *E, *d;            /* training-error scales and dead-zone bands (2n) */
    const double *eta, *r, *q;      /* EKF learning rates, R and Q (2n) */
    const double *bounds;           /* projection's per-weight bounds (2n, W), NULL: none */
    double kv, p_max, ramp_steps, sigma;
    long eta_is_ones, anti_windup, dead_zone, printed;
} dnbs_config;

typedef struct {
    dnbs_config c;
    long *fa, *ft;                  /* own copies of the factor tables */
    double *tanh_in;                /* (n, 4): [x1/s, x_d(k+2)/s] of the alpha net, [x1/s, x2/s] of the torque net */
    double *tanh_alpha;             /* (n): alpha / s, the torque net's third input */
    double *e1, *e2, *u, *active;   /* of the pending answer (n) */
    double *act, *eps, *eta_ramp;   /* training rows (2n) */
    double *tmp, *PH, *v;           /* scratch (W) */
    int has_active;
} dnbs_kernel;

void dnbs_free(dnbs_kernel *k) {
    if (!k) return;
    free(k->fa); free(k->ft); free(k->tanh_in); free(k->tanh_alpha); free(k->e1); free(k->e2); free(k->u);
    free(k->active); free(k->act); free(k->eps); free(k->eta_ramp); free(k->tmp); free(k->PH); free(k->v);
    free(k);
}

dnbs_kernel *dnbs_new(const dnbs_config *cfg) {
    dnbs_kernel *k = calloc(1, sizeof(dnbs_kernel));
    if (!k) return NULL;
    k->c = *cfg;
    long n = cfg->n, W = cfg->W;
    k->fa = malloc(sizeof(long) * cfg->La * cfg->Da);
    k->ft = malloc(sizeof(long) * cfg->Lt * cfg->Dt);
    k->tanh_in = malloc(sizeof(double) * n * 4);
    k->tanh_alpha = malloc(sizeof(double) * n);
    k->e1 = malloc(sizeof(double) * n);
    k->e2 = malloc(sizeof(double) * n);
    k->u = malloc(sizeof(double) * n);
    k->active = malloc(sizeof(double) * n);
    k->act = malloc(sizeof(double) * 2 * n);
    k->eps = malloc(sizeof(double) * 2 * n);
    k->eta_ramp = malloc(sizeof(double) * 2 * n);
    k->tmp = malloc(sizeof(double) * W);
    k->PH = malloc(sizeof(double) * W);
    k->v = malloc(sizeof(double) * W);
    if (!k->fa || !k->ft || !k->tanh_in || !k->tanh_alpha || !k->e1 || !k->e2 || !k->u || !k->active || !k->act
        || !k->eps || !k->eta_ramp || !k->tmp || !k->PH || !k->v) {
        dnbs_free(k);
        return NULL;
    }
    memcpy(k->fa, cfg->fa, sizeof(long) * cfg->La * cfg->Da);
    memcpy(k->ft, cfg->ft, sizeof(long) * cfg->Lt * cfg->Dt);
    k->c.fa = k->fa;
    k->c.ft = k->ft;
    return k;
}

double *dnbs_tanh_in(dnbs_kernel *k) { return k->tanh_in; }
double *dnbs_tanh_alpha(dnbs_kernel *k) { return k->tanh_alpha; }

/* HONN.regressor: term t = ext[f_t0] * ext[f_t1] * ... multiplied left to right (one factor: a copy) */
INLINE void regressor(const double *ext, const long *f, long L, long D, double *S) {
    for (long t = 0; t < L; t++) {
        const long *ft = f + t * D;
        double s = ext[ft[0]];
        if (D > 1) {
            s = ext[ft[0]] * ext[ft[1]];
            for (long j = 2; j < D; j++) s = s * ext[ft[j]];
        }
        S[t] = s;
    }
}

/* w_row^T H_row as numpy's add.reduce(w * H, axis=1) */
INLINE double dot_row(const double *w, const double *H, double *tmp, long W) {
    for (long j = 0; j < W; j++) tmp[j] = w[j] * H[j];
    return reduce_row(tmp, W);
}

/* Answer, step 1 of 3. in: (6, n) rows x1, x2, x_d, x_d_dot, x_d(k+2), active (read when has_active).
 * Fills tanh_in with the scaled inputs; the caller then applies np.tanh to it in place. */
void dnbs_answer_inputs(dnbs_kernel *k, const double *in, int has_active) {
    const dnbs_config *c = &k->c;
    long n = c->n;
    const double *x1 = in, *x2 = in + n, *ahead = in + 4 * n;
    for (long i = 0; i < n; i++) {
        double *T = k->tanh_in + 4 * i;
        T[0] = x1[i] * c->ia[0];
        T[1] = ahead[i] * c->ia[1];
        T[2] = x1[i] * c->it[0];
        T[3] = x2[i] * c->it[1];
    }
    k->has_active = has_active;
    if (has_active) memcpy(k->active, in + 5 * n, sizeof(double) * n);
}

/* Answer, step 2 of 3: the alpha networks' regressors and alpha (eq. 25 with the robust term); fills
 * tanh_alpha with alpha / s; the caller then applies np.tanh to it in place. */
void dnbs_answer_alpha(dnbs_kernel *k, const double *in) {
    const dnbs_config *c = &k->c;
    long n = c->n, W = c->W;
    const double *x1 = in, *pos = in + 2 * n, *vel = in + 3 * n;
    for (long i = 0; i < n; i++) {
        const double *T = k->tanh_in + 4 * i;
        double ext[3] = {1.0, T[0], T[1]};
        double *H = c->H + i * W;
        regressor(ext, c->fa, c->La, c->Da, H + c->oa);
        double e1 = pos[i] - x1[i];
        double alpha = c->A[i] * dot_row(c->w + i * W, H, k->tmp, W) + c->ka[i] * e1;
        if (c->kv != 0.0) alpha = alpha + vel[i];
        k->e1[i] = e1;
        c->alpha[i] = alpha;
        k->tanh_alpha[i] = alpha * c->it[2];
    }
}

/* Answer, step 3 of 3: the torque networks' regressors and the torques; u_out (n) gets them clipped to
 * the joints' torque limits, torque_unsaturated the unclipped ones. */
void dnbs_answer_torque(dnbs_kernel *k, const double *in, double *u_out) {
    const dnbs_config *c = &k->c;
    long n = c->n, W = c->W;
    const double *x2 = in + n;
    for (long i = 0; i < n; i++) {
        const double *T = k->tanh_in + 4 * i;
        double ext[4] = {1.0, T[2], T[3], k->tanh_alpha[i]};
        double *H = c->H + (n + i) * W;
        regressor(ext, c->ft, c->Lt, c->Dt, H + c->ot);
        double e2 = c->alpha[i] - x2[i];
        double u = c->U[i] * dot_row(c->w + (n + i) * W, H, k->tmp, W) + c->ku[i] * e2;
        k->e2[i] = e2;
        k->u[i] = u;
        c->u_unsat[i] = u;
        u_out[i] = np_min(np_max(u, -c->lim[i]), c->lim[i]);
    }
}

/* EKFBank.update of every row (act NULL: every row trains); see pa10_dnbs/core/ekf.py. Inlined once per
 * width below, so that a constant W unrolls the sums (the same operations in the same order). */
INLINE void ekf_update_width(dnbs_kernel *k, const long W, const double *eta, int eta_is_ones, const double *act) {
    const dnbs_config *c = &k->c;
    long rows = 2 * c->n;
    double *tmp = k->tmp, *PH = k->PH, *v = k->v;
    for (long i = 0; i < rows; i++) {
        double *P = c->P + i * W * W, *w = c->w + i * W;
        const double *H = c->H + i * W;
        for (long j = 0; j < W; j++) {
            const double *Pj = P + j * W;
            for (long l = 0; l < W; l++) tmp[l] = Pj[l] * H[l];
            PH[j] = reduce_row(tmp, W);
        }
        for (long l = 0; l < W; l++) tmp[l] = H[l] * PH[l];
        double hph = reduce_row(tmp, W);
        double m = 1.0 / (c->r[i] + hph);
        double sqrt_m = sqrt(m);
        double f = act ? sqrt_m * act[i] : sqrt_m;
        for (long l = 0; l < W; l++) v[l] = PH[l] * f;
        double step = eta_is_ones ? sqrt_m * k->eps[i] : (eta[i] * sqrt_m) * k->eps[i];
        for (long l = 0; l < W; l++) w[l] += v[l] * step;
        for (long j = 0; j < W; j++)
            for (long l = 0; l < W; l++) P[j * W + l] -= v[j] * v[l];
        double q = act ? c->q[i] * act[i] : c->q[i];
        for (long l = 0; l < W; l++) {
            double *dl = P + l * (W + 1);
            if (c->p_max == INFINITY || *dl < c->p_max) *dl += q;
        }
        c->hph[i] = hph;
    }
}

static void ekf_update(dnbs_kernel *k, const double *eta, int eta_is_ones, const double *act) {
    switch (k->c.W) {  /* the widths of the shipped configs' networks, then any other */
    case 12: ekf_update_width(k, 12, eta, eta_is_ones, act); break;
    case 20: ekf_update_width(k, 20, eta, eta_is_ones, act); break;
    default: ekf_update_width(k, k->c.W, eta, eta_is_ones, act);
    }
}

/* DNBSControllers.learn up to its guard, for the answer just given; steps: the controller's step count
 * before this training. Returns 0 when the guard's cheap check passes (every w and H^T P H finite,
 * H^T P H >= 0), 1 when it fails (the caller then runs the full guard). */
int dnbs_learn(dnbs_kernel *k, long steps) {
    const dnbs_config *c = &k->c;
    long n = c->n, rows = 2 * n, W = c->W;
    const double *act = NULL;
    if (k->has_active) {
        for (long i = 0; i < n; i++) k->act[i] = k->act[n + i] = k->active[i];
        act = k->act;
    }
    double *e2t = k->eps + n;  /* e2 as trained: -e2 for the printed sign */
    for (long i = 0; i < n; i++) {
        k->eps[i] = k->e1[i];
        e2t[i] = c->printed ? -k->e2[i] : k->e2[i];
    }
    if (c->anti_windup) {
        int any = 0;
        for (long i = 0; i < n; i++) any |= fabs(k->u[i]) >= c->lim[i];
        if (any) {
            for (long i = 0; i < n; i++) {
                double base = k->has_active ? k->active[i] : 1.0;
                int sat = fabs(k->u[i]) >= c->lim[i];
                k->act[i] = base * (1.0 - (double)(sat && (k->e1[i] * k->u[i] > 0.0)));
                k->act[n + i] = base * (1.0 - (double)(sat && (e2t[i] * k->u[i] > 0.0)));
            }
            act = k->act;
        }
    }
    if (c->dead_zone)
        for (long i = 0; i < rows; i++) k->eps[i] -= np_min(np_max(k->eps[i], -c->d[i]), c->d[i]);
    for (long i = 0; i < rows; i++) k->eps[i] = k->eps[i] / c->E[i];
    const double *eta = c->eta;
    int ones = (int)c->eta_is_ones;
    if (c->ramp_steps != 0.0 && (double)steps < c->ramp_steps) {
        double f = (double)steps / c->ramp_steps;
        for (long i = 0; i < rows; i++) k->eta_ramp[i] = c->eta[i] * f;
        eta = k->eta_ramp;
        ones = 0;
    }
    ekf_update(k, eta, ones, act);
    if (c->sigma != 0.0) {
        for (long i = 0; i < rows; i++) {
            double leak = c->sigma * fabs(k->eps[i]);
            if (act) leak *= act[i];
            double keep = 1.0 - np_min(1.0, leak);
            for (long l = 0; l < W; l++) c->w[i * W + l] *= keep;
        }
    }
    if (c->bounds)
        for (long l = 0; l < rows * W; l++) c->w[l] = np_min(np_max(c->w[l], -c->bounds[l]), c->bounds[l]);
    double total = psum(c->w, rows * W) + reduce_row(c->hph, rows);
    double lowest = c->hph[0];
    for (long i = 1; i < rows; i++) lowest = np_min(lowest, c->hph[i]);
    return (isfinite(total) && lowest >= 0.0) ? 0 : 1;
}
