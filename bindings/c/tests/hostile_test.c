/* Hostile input through the C ABI (driven by tests/c_programs.rs):
 *
 *   hostile_test GOOD BAD
 * GOOD: a SOURCE that opens; BAD: a table with one corrupt chunk. Every check prints
 * "FAIL ..." to stderr and makes the exit status 1; a crash fails the Rust side.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brdftab.h"

static int failures = 0;
#define CHECK(cond, what)                                                              \
    do {                                                                               \
        if (!(cond)) {                                                                 \
            fprintf(stderr, "FAIL %s (last error: %s)\n", what, brdftab_last_error()); \
            failures++;                                                                \
        }                                                                              \
    } while (0)

/* The counts whose byte sizes overflow: n * 3 wraps (SIZE_MAX/3 + 1), n * 24 wraps
 * (SIZE_MAX/24 + 1), n * 16 wraps (SIZE_MAX/2 + 1 for u), and the largest. */
static const size_t huge[] = {SIZE_MAX / 3 + 1, SIZE_MAX / 24 + 1, SIZE_MAX / 2 + 1, SIZE_MAX,
                              (size_t)PTRDIFF_MAX / 24 + 1};

static int is_zero(const double *v, size_t n) {
    for (size_t i = 0; i < n; i++)
        if (v[i] != 0.0) return 0;
    return 1;
}

static void overflowing_counts(const brdftab_brdf *b) {
    double wi[3] = {0, 0, 1}, wo[3] = {0, 0, 1}, u[2] = {0.5, 0.5}, swi[3], pdf[1];
    float f[16], w[16];
    for (size_t k = 0; k < sizeof huge / sizeof huge[0]; k++) {
        char what[96];
        snprintf(what, sizeof what, "eval n = %zu is -1 with a message", huge[k]);
        CHECK(brdftab_eval(b, huge[k], wi, wo, f) == -1 && strlen(brdftab_last_error()) > 0, what);
        snprintf(what, sizeof what, "pdf n = %zu is -1 with a message", huge[k]);
        CHECK(brdftab_pdf(b, huge[k], wi, wo, pdf) == -1 && strlen(brdftab_last_error()) > 0, what);
        snprintf(what, sizeof what, "sample n = %zu is -1, not a caught panic", huge[k]);
        CHECK(brdftab_sample(b, huge[k], wo, u, swi, pdf, w) == -1 &&
                  strlen(brdftab_last_error()) > 0 && !strstr(brdftab_last_error(), "panic"),
              what);
        CHECK(!strstr(brdftab_last_error(), "panic"), "no panic behind the -1");
        unsigned char d[1];
        snprintf(what, sizeof what, "sample_delta n = %zu is -1, not a caught panic", huge[k]);
        CHECK(brdftab_sample_delta(b, huge[k], wo, u, swi, pdf, w, d) == -1 &&
                  strlen(brdftab_last_error()) > 0 && !strstr(brdftab_last_error(), "panic"),
              what);
        double nm[2] = {500.0, 600.0};
        snprintf(what, sizeof what, "eval_spectral n = %zu is -1, not a caught panic", huge[k]);
        CHECK(brdftab_eval_spectral(b, huge[k], wi, wo, 2, nm, f) == -1 &&
                  strlen(brdftab_last_error()) > 0 && !strstr(brdftab_last_error(), "panic"),
              what);
        snprintf(what, sizeof what, "sample_spectral n = %zu is -1, not a caught panic", huge[k]);
        CHECK(brdftab_sample_spectral(b, huge[k], wo, u, 2, nm, swi, pdf, w, d) == -1 &&
                  strlen(brdftab_last_error()) > 0 && !strstr(brdftab_last_error(), "panic"),
              what);
    }
    /* The handle still works. */
    CHECK(brdftab_eval(b, 1, wi, wo, f) == 0 && f[0] > 0, "eval after the hostile counts");
}

/* NaN, infinite and zero directions: 0, never an error, never a crash. */
static void non_finite_directions(const brdftab_brdf *b) {
    size_t c = brdftab_channels(b);
    double bad[4][3] = {{NAN, 0, 1}, {0, INFINITY, 1}, {0, 0, 0}, {0, 0, -INFINITY}};
    double up[3] = {0.2, 0.1, 0.9}, u[2] = {0.3, 0.7}, nan_u[2] = {NAN, 0.5};
    for (int k = 0; k < 4; k++) {
        float f[16];
        double pdf = -1, swi[3] = {7, 7, 7}, spdf = -1, fd[16];
        float w[16];
        for (size_t i = 0; i < c; i++) f[i] = w[i] = -1;
        CHECK(brdftab_eval(b, 1, bad[k], up, f) == 0, "eval with a non-finite wi succeeds");
        for (size_t i = 0; i < c; i++) fd[i] = f[i];
        CHECK(is_zero(fd, c), "f_r(non-finite wi) = 0");
        CHECK(brdftab_eval(b, 1, up, bad[k], f) == 0, "eval with a non-finite wo succeeds");
        for (size_t i = 0; i < c; i++) fd[i] = f[i];
        CHECK(is_zero(fd, c), "f_r(non-finite wo) = 0");
        CHECK(brdftab_pdf(b, 1, bad[k], up, &pdf) == 0 && pdf == 0, "pdf(non-finite wi) = 0");
        CHECK(brdftab_pdf(b, 1, up, bad[k], &pdf) == 0 && pdf == 0, "pdf(non-finite wo) = 0");
        CHECK(brdftab_sample(b, 1, bad[k], u, swi, &spdf, w) == 0, "sample(non-finite wo)");
        for (size_t i = 0; i < c; i++) fd[i] = w[i];
        CHECK(is_zero(swi, 3) && spdf == 0 && is_zero(fd, c), "no sample for a non-finite wo");
    }
    double swi[3] = {7, 7, 7}, spdf = -1, fd[16];
    float w[16];
    CHECK(brdftab_sample(b, 1, up, nan_u, swi, &spdf, w) == 0, "sample(NaN u)");
    for (size_t i = 0; i < c; i++) fd[i] = w[i];
    CHECK(is_zero(swi, 3) && spdf == 0 && is_zero(fd, c), "no sample for a NaN u");
}

/* No wavelengths (k = 0): nm and the values may be NULL in both spectral calls (the header),
 * and sample_spectral still draws what sample_delta draws. */
static void no_wavelengths(const brdftab_brdf *b) {
    double wi[3] = {0.3, 0.1, 0.9}, wo[3] = {-0.2, 0.3, 0.8}, u[2] = {0.3, 0.4};
    double swi[3] = {7, 7, 7}, pdf = -1, dwi[3], dpdf;
    float w[16];
    unsigned char d = 7, dd;
    CHECK(brdftab_eval_spectral(b, 1, wi, wo, 0, NULL, NULL) == 0,
          "eval_spectral with k = 0 and f NULL succeeds");
    CHECK(brdftab_sample_spectral(b, 1, wo, u, 0, NULL, swi, &pdf, NULL, &d) == 0,
          "sample_spectral with k = 0 and weight NULL succeeds");
    CHECK(brdftab_sample_delta(b, 1, wo, u, dwi, &dpdf, w, &dd) == 0, "sample_delta");
    CHECK(memcmp(swi, dwi, sizeof swi) == 0 && pdf == dpdf && d == dd,
          "sample_spectral with k = 0 draws what sample_delta draws");
}

/* A corrupt chunk met lazily: -1 with the checksum error, and the handle stays failed. */
static void corrupt_table(const char *path) {
    brdftab_brdf *b = brdftab_open(path); /* lazy: the open succeeds */
    CHECK(b != NULL, "a corrupt table opens lazily");
    if (!b) return;
    enum { N = 4096 };
    static double wi[3 * N], wo[3 * N], u[2 * N], pdf[N], swi[3 * N];
    static float f[3 * N], w[3 * N];
    for (int k = 0; k < N; k++) { /* pairs over the hemisphere */
        double t = 1.5 * (k % 64) / 64.0, p = 6.283 * (k / 64) / 64.0;
        wi[3 * k] = sin(t) * cos(p), wi[3 * k + 1] = sin(t) * sin(p), wi[3 * k + 2] = cos(t);
        wo[3 * k] = -0.3, wo[3 * k + 1] = 0.1, wo[3 * k + 2] = 0.9;
        u[2 * k] = (k % 61) / 61.0, u[2 * k + 1] = (k % 59) / 59.0;
    }
    /* The last pair at normal incidence both ways (θh = 0: chunk 0, the corrupt one). */
    wi[3 * N - 3] = wi[3 * N - 2] = wo[3 * N - 3] = wo[3 * N - 2] = 0;
    wi[3 * N - 1] = wo[3 * N - 1] = 1;
    CHECK(brdftab_eval(b, N, wi, wo, f) == -1 && strstr(brdftab_last_error(), "checksum"),
          "eval of a corrupt chunk is -1 with the checksum error");
    double one[3] = {0, 0, 1};
    float f1[3];
    CHECK(brdftab_eval(b, 1, one, one, f1) == -1 && strstr(brdftab_last_error(), "checksum"),
          "the handle stays failed");
    CHECK(brdftab_pdf(b, N, wi, wo, pdf) == -1 && strstr(brdftab_last_error(), "checksum"),
          "pdf on a failed handle");
    CHECK(brdftab_sample(b, N, wo, u, swi, pdf, w) == -1 &&
              strstr(brdftab_last_error(), "checksum"),
          "sample on a failed handle");
    static unsigned char d[N];
    CHECK(brdftab_sample_delta(b, N, wo, u, swi, pdf, w, d) == -1 &&
              strstr(brdftab_last_error(), "checksum"),
          "sample_delta on a failed handle");
    brdftab_close(b);
    brdftab_open_options eager = {.eager = 1};
    CHECK(brdftab_open_with(path, &eager) == NULL && strstr(brdftab_last_error(), "checksum"),
          "an eager open of a corrupt table fails");
}

/* Table names (the library's store::name rule): `DB#` with nothing after the '#' and names with
 * control characters are -1 naming the field; `x.btdb#` was baked into a file of that name. */
static void table_names(const char *near) {
    const char *spec = "{\"model\": \"lambert\", \"kd\": 0.5}";
    char out[4096];
    snprintf(out, sizeof out, "%s.names.btdb#", near);
    CHECK(brdftab_bake(spec, out, "{\"preset\": \"small\"}") == -1 &&
              strstr(brdftab_last_error(), "output"),
          "bake to DB# (no name) is -1 naming output");
    FILE *f = fopen(out, "rb");
    CHECK(f == NULL, "no file named DB# written");
    if (f) fclose(f);
    CHECK(brdftab_open(out) == NULL && strstr(brdftab_last_error(), "source"),
          "open DB# (no name) is NULL naming source");
    snprintf(out, sizeof out, "%s.names.btdb#a\tb", near);
    CHECK(brdftab_bake(spec, out, "{\"preset\": \"small\"}") == -1 &&
              strstr(brdftab_last_error(), "control character"),
          "bake to DB#NAME with a tab in NAME is -1");
    snprintf(out, sizeof out, "%s.names.btdb", near);
    CHECK(brdftab_bake(spec, out, "{\"preset\": \"small\", \"name\": \"a\\u0001b\"}") == -1 &&
              strstr(brdftab_last_error(), "name"),
          "a name setting with a control character is -1 naming name");
}

/* Calls from an atexit handler, after this thread's storage is destroyed: they work (no abort
 * from a panic outside the guard), and a failure is still -1 with some message. */
static void calls_at_exit(void) {
    brdftab_brdf *b = brdftab_open("{\"model\": \"lambert\", \"kd\": 0.5}");
    double wi[3] = {0, 0.6, 0.8}, wo[3] = {0, 0, 1};
    float f[3] = {0, 0, 0};
    CHECK(b != NULL && brdftab_eval(b, 1, wi, wo, f) == 0 && f[0] == 0.5f,
          "open and eval from an atexit handler");
    CHECK(brdftab_eval(NULL, 1, wi, wo, f) == -1 && strlen(brdftab_last_error()) > 0,
          "a failure from an atexit handler is -1 with a message");
    brdftab_close(b);
    if (failures) _Exit(1);
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: %s GOOD BAD\n", argv[0]);
        return 2;
    }
    brdftab_brdf *b = brdftab_open(argv[1]);
    if (!b) {
        fprintf(stderr, "error: %s\n", brdftab_last_error());
        return 1;
    }
    /* The header's version is the library's (both are the crate's). */
    char v[64];
    snprintf(v, sizeof v, "%d.%d.%d", BRDFTAB_VERSION_MAJOR, BRDFTAB_VERSION_MINOR,
             BRDFTAB_VERSION_PATCH);
    CHECK(strcmp(v, BRDFTAB_VERSION) == 0 && strcmp(BRDFTAB_VERSION, brdftab_version()) == 0,
          "BRDFTAB_VERSION_* and BRDFTAB_VERSION are brdftab_version()");
    atexit(calls_at_exit);
    overflowing_counts(b);
    non_finite_directions(b);
    no_wavelengths(b);
    brdftab_close(b);
    corrupt_table(argv[2]);
    table_names(argv[2]);
    return failures ? 1 : 0;
}
