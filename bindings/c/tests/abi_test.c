/* The C side of tests/c_programs.rs: drives every function of brdftab.h from C.
 *
 *   abi_test SOURCE PAIRS OUT
 * PAIRS: n lines "wix wiy wiz wox woy woz u0 u1". OUT: per pair one line
 *   f_1..f_c pdf wi_x wi_y wi_z spdf w_1..w_c
 * then "albedo a_1..a_c" for θ = 30°. Checks of bad arguments and of two threads on one handle
 * print "FAIL ..." to stderr and make the exit status 1.
 */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brdftab.h"

#define BRDFTAB_PI 3.14159265358979323846

static int failures = 0;
#define CHECK(cond, what)                                                   \
    do {                                                                    \
        if (!(cond)) {                                                      \
            fprintf(stderr, "FAIL %s (last error: %s)\n", what, brdftab_last_error()); \
            failures++;                                                     \
        }                                                                   \
    } while (0)

struct job {
    const brdftab_brdf *b;
    size_t n;
    const double *wi, *wo;
    float *f;
    int rc;
};

static void *run_eval(void *p) {
    struct job *j = p;
    for (int rep = 0; rep < 20 && j->rc == 0; rep++) j->rc = brdftab_eval(j->b, j->n, j->wi, j->wo, j->f);
    return NULL;
}

int main(int argc, char **argv) {
    if (argc != 4) {
        fprintf(stderr, "usage: %s SOURCE PAIRS OUT\n", argv[0]);
        return 2;
    }
    FILE *in = fopen(argv[2], "r");
    if (!in) return 2;
    size_t cap = 1024, n = 0;
    double *wi = malloc(cap * 3 * sizeof(double)), *wo = malloc(cap * 3 * sizeof(double)),
           *u = malloc(cap * 2 * sizeof(double));
    for (;;) {
        if (n == cap) {
            cap *= 2;
            wi = realloc(wi, cap * 3 * sizeof(double));
            wo = realloc(wo, cap * 3 * sizeof(double));
            u = realloc(u, cap * 2 * sizeof(double));
        }
        if (fscanf(in, "%lf %lf %lf %lf %lf %lf %lf %lf", &wi[3 * n], &wi[3 * n + 1], &wi[3 * n + 2],
                   &wo[3 * n], &wo[3 * n + 1], &wo[3 * n + 2], &u[2 * n], &u[2 * n + 1]) != 8)
            break;
        n++;
    }
    fclose(in);

    /* A bad SOURCE: NULL and a message naming it. */
    brdftab_brdf *bad = brdftab_open("/no/such/file.btdb");
    CHECK(bad == NULL && strstr(brdftab_last_error(), "/no/such/file.btdb"), "bad source");
    CHECK(brdftab_open(NULL) == NULL && strlen(brdftab_last_error()) > 0, "NULL source");
    CHECK(brdftab_open("{\"model\": \"no_such_model\"}") == NULL, "unknown model");

    /* The options struct's size: 0 (this first layout) and sizeof open; a size smaller than the
     * first layout fails; a later header's larger struct opens while its new fields are zero
     * and fails, naming the byte, once one is set (a field this library cannot honour). */
    {
        const char *lam = "{\"model\": \"lambert\", \"kd\": 0.5}";
        brdftab_open_options o = {0};
        brdftab_brdf *h = brdftab_open_with(lam, &o);
        CHECK(h != NULL, "size 0: the first layout");
        brdftab_close(h);
        o.size = sizeof o;
        h = brdftab_open_with(lam, &o);
        CHECK(h != NULL, "size = sizeof(brdftab_open_options)");
        brdftab_close(h);
        o.size = 8;
        CHECK(brdftab_open_with(lam, &o) == NULL && strstr(brdftab_last_error(), "size 8"),
              "a size smaller than the first layout");
        struct later { brdftab_open_options o; double added; } big;
        memset(&big, 0, sizeof big);
        big.o.size = sizeof big;
        h = brdftab_open_with(lam, &big.o);
        CHECK(h != NULL, "a later header's struct with its new field at zero");
        brdftab_close(h);
        big.added = 1.0;
        CHECK(brdftab_open_with(lam, &big.o) == NULL &&
                  strstr(brdftab_last_error(), "does not know") != NULL,
              "a later header's field set");
    }

    brdftab_brdf *b = brdftab_open(argv[1]);
    if (!b) {
        fprintf(stderr, "error: %s\n", brdftab_last_error());
        return 1;
    }
    CHECK(strcmp(brdftab_last_error(), "") == 0, "success clears the error");
    size_t c = brdftab_channels(b);
    CHECK(c > 0 && brdftab_channel_name(b, 0) != NULL, "channels");
    CHECK(brdftab_channel_name(b, c) == NULL, "channel name out of range");
    float *f = malloc(n * c * sizeof(float)), *w = malloc(n * c * sizeof(float));
    double *pdf = malloc(n * sizeof(double)), *swi = malloc(n * 3 * sizeof(double)),
           *spdf = malloc(n * sizeof(double)), *alb = malloc(c * sizeof(double));

    /* Bad arguments: -1 with a message, never a crash; n = 0 succeeds with NULL pointers. */
    CHECK(brdftab_eval(NULL, 1, wi, wo, f) == -1 && strstr(brdftab_last_error(), "NULL"), "NULL handle");
    CHECK(brdftab_eval(b, 1, NULL, wo, f) == -1, "NULL wi");
    CHECK(brdftab_pdf(b, 1, wi, wo, NULL) == -1, "NULL pdf");
    CHECK(brdftab_sample(b, 1, wo, NULL, swi, spdf, w) == -1, "NULL u");
    CHECK(brdftab_albedo(b, NAN, alb) == -1, "NaN theta");
    /* Outside [0, pi/2): -1 (theta = -1 gave the albedo at 1 rad, theta = 3 gave 0, theta = pi/2
     * a light 6e-17 above the horizon, where Ward's albedo diverges). */
    CHECK(brdftab_albedo(b, -1.0, alb) == -1, "negative theta");
    CHECK(brdftab_albedo(b, 3.0, alb) == -1, "theta beyond pi/2");
    CHECK(strstr(brdftab_last_error(), "theta") != NULL, "theta named in the error");
    CHECK(brdftab_albedo(b, BRDFTAB_PI / 2.0, alb) == -1, "theta = pi/2 is refused");
    CHECK(strstr(brdftab_last_error(), "horizon") != NULL, "the horizon named in the error");
    CHECK(brdftab_albedo(b, nextafter(BRDFTAB_PI / 2.0, 0.0), alb) == 0, "just below pi/2");
    CHECK(brdftab_albedo(NULL, 0.5, alb) == -1, "NULL albedo handle");
    /* Light from an azimuth: phi = 0 is brdftab_albedo; GGX (0.01, 1) from phi = pi/2 is
     * (1, 0.01) from phi = 0 (each integral to 1e-6); a non-finite phi is -1 naming phi. */
    {
        brdftab_brdf *an = brdftab_open("{\"model\": \"ggx\", \"alpha_x\": 0.01, \"alpha_y\": 1}");
        brdftab_brdf *tu = brdftab_open("{\"model\": \"ggx\", \"alpha_x\": 1, \"alpha_y\": 0.01}");
        CHECK(an && tu, "anisotropic GGX handles");
        double a0[3], a1[3], at[3], want[3];
        CHECK(brdftab_albedo(an, 1.2, a0) == 0 && brdftab_albedo_at(an, 1.2, 0.0, a1) == 0,
              "albedo_at phi = 0");
        CHECK(memcmp(a0, a1, sizeof a0) == 0, "albedo_at phi = 0 is brdftab_albedo");
        CHECK(brdftab_albedo_at(an, 1.2, BRDFTAB_PI / 2.0, at) == 0 &&
                  brdftab_albedo(tu, 1.2, want) == 0,
              "albedo_at phi = pi/2");
        int near = 1;
        for (int i = 0; i < 3; i++) near &= fabs(at[i] - want[i]) <= 5e-6 * want[i];
        CHECK(near && fabs(at[0] - a0[0]) > 1e-2 * a0[0], "an anisotropic albedo turns with phi");
        CHECK(brdftab_albedo_at(an, 1.2, NAN, at) == -1 && strstr(brdftab_last_error(), "phi"),
              "a NaN phi");
        brdftab_close(an);
        brdftab_close(tu);
    }
    CHECK(brdftab_eval(b, 0, NULL, NULL, NULL) == 0, "n = 0");
    CHECK(brdftab_eval(NULL, 0, NULL, NULL, NULL) == 0, "n = 0, NULL handle");
    CHECK(brdftab_sample(b, 0, NULL, NULL, NULL, NULL, NULL) == 0, "sample n = 0");
    brdftab_close(NULL);

    CHECK(brdftab_eval(b, n, wi, wo, f) == 0, "eval");
    CHECK(brdftab_pdf(b, n, wi, wo, pdf) == 0, "pdf");
    CHECK(brdftab_sample(b, n, wo, u, swi, spdf, w) == 0, "sample");
    {
        /* eval_pdf: the batch is eval's and pdf's values exactly; one pair is the source's
         * eval_pdf (shared work, the same math: f32 rounding of f, f64 of the pdf). */
        float *f2 = malloc(n * c * sizeof(float));
        double *p2 = malloc(n * sizeof(double));
        CHECK(brdftab_eval_pdf(b, n, wi, wo, f2, p2) == 0, "eval_pdf");
        for (size_t k = 0; k < n; k++) {
            CHECK(p2[k] == pdf[k], "eval_pdf's batch pdf is pdf's");
            for (size_t i = 0; i < c; i++) CHECK(f2[k * c + i] == f[k * c + i], "eval_pdf's batch f is eval's");
        }
        for (size_t k = 0; k < n; k++) {
            float f1[64];
            double p1;
            CHECK(brdftab_eval_pdf(b, 1, wi + 3 * k, wo + 3 * k, f1, &p1) == 0, "eval_pdf of one pair");
            CHECK(fabs(p1 - pdf[k]) <= 1e-12 * pdf[k], "eval_pdf of one pair: pdf");
            for (size_t i = 0; i < c; i++)
                CHECK(fabs(f1[i] - f[k * c + i]) <= 4e-7f * fabs(f[k * c + i]), "eval_pdf of one pair: f");
        }
        CHECK(brdftab_eval_pdf(b, 1, wi, wo, f2, NULL) == -1, "NULL pdf of eval_pdf");
        CHECK(brdftab_eval_pdf(b, 1, wi, wo, NULL, p2) == -1, "NULL f of eval_pdf");
        CHECK(brdftab_eval_pdf(b, 0, NULL, NULL, NULL, NULL) == 0, "eval_pdf n = 0");
        free(f2);
        free(p2);
    }
    {
        /* u outside [0, 1) has no sample, like a NaN in u (u = -3 drew one before). */
        double wo1[3] = {0.3, 0.0, 0.95}, bad[4][2] = {{-3.0, 0.5}, {1.5, 0.2}, {1.0, 0.0}, {0.5, 0.25}};
        double wi1[3], p1;
        float w1[64];
        for (int k = 0; k < 4; k++) {
            CHECK(brdftab_sample(b, 1, wo1, bad[k], wi1, &p1, w1) == 0, "sample call");
            CHECK((k < 3) == (p1 == 0.0 && wi1[0] == 0.0 && wi1[1] == 0.0 && wi1[2] == 0.0),
                  "u outside [0, 1) has no sample; u inside has one");
        }
    }
    {
        /* A direction of any finite nonzero length is a direction: scaled by 1e308 or 1e-300
         * (squared lengths that overflow or underflow) eval, pdf and sample give what the unit
         * pair gives (pdf gave 0 at 1e308 while eval normalized). */
        double wi1[3] = {-0.3, 0.1, 0.9}, wo1[3] = {0.4, 0.2, 0.85}, u1[2] = {0.3, 0.6};
        float f1[64], f2[64], w1[64], w2[64];
        double p1, p2, s1[3], s2[3], sp1, sp2;
        CHECK(brdftab_eval(b, 1, wi1, wo1, f1) == 0 && brdftab_pdf(b, 1, wi1, wo1, &p1) == 0 &&
              brdftab_sample(b, 1, wo1, u1, s1, &sp1, w1) == 0, "unit pair");
        double scales[2] = {1e308, 1e-300};
        for (int k = 0; k < 2; k++) {
            double a[3], o[3];
            for (int i = 0; i < 3; i++) {
                a[i] = wi1[i] / sqrt(0.91) * scales[k];
                o[i] = wo1[i] / sqrt(0.9225) * scales[k];
            }
            CHECK(brdftab_eval(b, 1, a, o, f2) == 0 && brdftab_pdf(b, 1, a, o, &p2) == 0 &&
                  brdftab_sample(b, 1, o, u1, s2, &sp2, w2) == 0, "scaled pair");
            for (size_t i = 0; i < c; i++)
                CHECK(fabs(f2[i] - f1[i]) <= 1e-5 * fabs(f1[i]) && fabs(w2[i] - w1[i]) <= 1e-5 * fabs(w1[i]),
                      "eval and sample weights of a scaled pair");
            CHECK(fabs(p2 - p1) <= 1e-9 * p1 && fabs(sp2 - sp1) <= 1e-9 * sp1 && p1 > 0.0,
                  "pdf and sample pdf of a scaled pair");
            CHECK(fabs(s2[0] - s1[0]) + fabs(s2[1] - s1[1]) + fabs(s2[2] - s1[2]) < 1e-9,
                  "sampled direction of a scaled wo");
        }
    }
    CHECK(brdftab_albedo(b, 30.0 * BRDFTAB_PI / 180.0, alb) == 0, "albedo");
    {
        /* brdftab_sample_delta: the same draws as brdftab_sample, and a delta flag per draw — a
         * sum's mirror term flagged (its pdf the probability of that term, below 1), its
         * diffuse term not; this source (argv[1]) has no delta lobe. */
        unsigned char *d = malloc(n);
        double *swi2 = malloc(n * 3 * sizeof(double)), *spdf2 = malloc(n * sizeof(double));
        float *w2 = malloc(n * c * sizeof(float));
        CHECK(brdftab_sample_delta(b, n, wo, u, swi2, spdf2, w2, NULL) == -1 &&
              strstr(brdftab_last_error(), "delta") != NULL, "NULL delta");
        CHECK(brdftab_sample_delta(b, 0, NULL, NULL, NULL, NULL, NULL, NULL) == 0, "n = 0");
        memset(d, 7, n);
        CHECK(brdftab_sample_delta(b, n, wo, u, swi2, spdf2, w2, d) == 0, "sample_delta");
        CHECK(memcmp(swi, swi2, n * 3 * sizeof(double)) == 0 &&
              memcmp(spdf, spdf2, n * sizeof(double)) == 0 &&
              memcmp(w, w2, n * c * sizeof(float)) == 0, "the draws of brdftab_sample");
        int none = 1;
        for (size_t k = 0; k < n; k++) none &= d[k] == 0;
        CHECK(none, "no delta lobe, no delta draw");
        brdftab_brdf *m = brdftab_open(
            "{\"model\": \"sum\", \"terms\": [{\"model\": \"lambert\", \"kd\": 0.2},"
            " {\"model\": \"mirror\"}]}");
        CHECK(m != NULL && (brdftab_flags(m) & BRDFTAB_DELTA), "a sum with a mirror term");
        double wo1[3] = {0.6, 0.0, 0.8}, wi1[3], p1;
        float w1[3];
        int deltas = 0, smooth = 0;
        for (int k = 0; k < 64; k++) {
            double u1[2] = {(k + 0.5) / 64.0, 0.3};
            unsigned char d1 = 9;
            CHECK(brdftab_sample_delta(m, 1, wo1, u1, wi1, &p1, w1, &d1) == 0, "sum sample");
            CHECK(d1 == 0 || d1 == 1, "a flag is 0 or 1");
            if (d1) {
                deltas++;
                CHECK(fabs(wi1[0] + 0.6) < 1e-12 && fabs(wi1[2] - 0.8) < 1e-12 && p1 < 1.0,
                      "a mirror draw: the mirror direction, the term's probability");
            } else {
                smooth++;
            }
        }
        CHECK(deltas > 0 && smooth > 0, "both terms drawn");
        brdftab_close(m);
        /* brdftab_eval_spectral / brdftab_sample_spectral at wavelengths of the call: what a
         * handle opened at those wavelengths gives at its channels. */
        double nm[3] = {450.0, 531.5, 690.0}, nan_nm[2] = {500.0, NAN};
        brdftab_open_options at = {.n_wavelengths = 3, .wavelengths = nm};
        const char *ggx = "{\"model\": \"ggx\", \"alpha\": 0.3, \"fresnel\": {\"conductor\": \"Au\"}}";
        const char *gold = "{\"model\": \"mirror\", \"fresnel\": {\"conductor\": \"Au\"}}";
        brdftab_brdf *g = brdftab_open(ggx), *g3 = brdftab_open_with(ggx, &at);
        brdftab_brdf *au = brdftab_open(gold), *au3 = brdftab_open_with(gold, &at);
        CHECK(g && g3 && au && au3, "spectral handles");
        float fs[3 * 64], f3[3 * 64];
        CHECK(brdftab_eval_spectral(g, 64, wi, wo, 3, nm, fs) == 0, "eval_spectral");
        CHECK(brdftab_eval(g3, 64, wi, wo, f3) == 0, "eval at channels");
        int same = 1;
        for (int i = 0; i < 3 * 64; i++) same &= fabsf(fs[i] - f3[i]) <= 1e-5f * fabsf(f3[i]) + 1e-12f;
        CHECK(same, "eval_spectral = eval of a handle opened at those wavelengths");
        double u1[2] = {0.5, 0.5}, swi3[3], sp3;
        float ws[3], w3[3];
        unsigned char d1 = 0;
        CHECK(brdftab_sample_spectral(au, 1, wo1, u1, 3, nm, wi1, &p1, ws, &d1) == 0 && d1 == 1,
              "sample_spectral of a mirror: a delta draw");
        CHECK(brdftab_sample(au3, 1, wo1, u1, swi3, &sp3, w3) == 0, "sample at channels");
        CHECK(ws[0] == w3[0] && ws[1] == w3[1] && ws[2] == w3[2] && ws[0] < 0.5f && ws[2] > 0.9f,
              "the mirror's Fresnel term at each wavelength");
        CHECK(brdftab_eval_spectral(g, 1, wi, wo, 2, NULL, fs) == -1 &&
              strstr(brdftab_last_error(), "nm") != NULL, "NULL nm");
        CHECK(brdftab_eval_spectral(g, 1, wi, wo, 2, nan_nm, fs) == -1 &&
              strstr(brdftab_last_error(), "wavelength") != NULL, "NaN in nm");
        CHECK(brdftab_sample_spectral(au, 1, wo1, u1, 2, nan_nm, wi1, &p1, ws, &d1) == -1,
              "NaN in nm (sample)");
        CHECK(brdftab_eval_spectral(g, 1, wi, wo, 0, NULL, fs) == 0, "k = 0");
        CHECK(brdftab_eval_spectral(g, 1, wi, wo, 0, NULL, NULL) == 0, "k = 0: f may be NULL");
        brdftab_close(g);
        brdftab_close(g3);
        brdftab_close(au);
        brdftab_close(au3);
        free(d);
        free(swi2);
        free(spdf2);
        free(w2);
    }

    /* Two threads on one handle give what one thread gave, bit for bit. */
    float *f1 = malloc(n * c * sizeof(float)), *f2 = malloc(n * c * sizeof(float));
    struct job j1 = {b, n, wi, wo, f1, 0}, j2 = {b, n, wi, wo, f2, 0};
    pthread_t t1, t2;
    pthread_create(&t1, NULL, run_eval, &j1);
    pthread_create(&t2, NULL, run_eval, &j2);
    pthread_join(t1, NULL);
    pthread_join(t2, NULL);
    CHECK(j1.rc == 0 && j2.rc == 0, "threads succeeded");
    CHECK(memcmp(f, f1, n * c * sizeof(float)) == 0 && memcmp(f, f2, n * c * sizeof(float)) == 0,
          "threads agree with one thread");

    FILE *out = fopen(argv[3], "w");
    for (size_t k = 0; k < n; k++) {
        for (size_t i = 0; i < c; i++) fprintf(out, "%.9g ", f[k * c + i]);
        fprintf(out, "%.17g %.17g %.17g %.17g %.17g", pdf[k], swi[3 * k], swi[3 * k + 1], swi[3 * k + 2], spdf[k]);
        for (size_t i = 0; i < c; i++) fprintf(out, " %.9g", w[k * c + i]);
        fprintf(out, "\n");
    }
    fprintf(out, "albedo");
    for (size_t i = 0; i < c; i++) fprintf(out, " %.17g", alb[i]);
    fprintf(out, "\n");
    fclose(out);
    brdftab_close(b);
    free(wi); free(wo); free(u); free(f); free(w); free(pdf); free(swi); free(spdf); free(alb);
    free(f1); free(f2);
    return failures ? 1 : 0;
}
