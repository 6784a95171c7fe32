/* The request layer through the C ABI: bake, convert, fit and open with JSON settings.
 * Usage: request_test DIR. Prints what it computed (checked by c_programs.rs against the Rust
 * request layer) and exits 1 when a call does not fail or succeed as it must. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "brdftab.h"

static const char *LAMBERT = "{\"model\":\"lambert\",\"kd\":[0.1,0.2,0.3]}";
static int failures = 0;

static void expect_error(int rc, const char *what, const char *field) {
    const char *msg = brdftab_last_error();
    if (rc != -1 || strstr(msg, field) == NULL) {
        fprintf(stderr, "%s: rc %d, message \"%s\" (wanted -1 naming %s)\n", what, rc, msg, field);
        failures++;
    } else {
        printf("error %s: %s\n", what, msg);
    }
}

static void print_normal(const char *label, const char *source, const char *settings) {
    brdftab_brdf *b = brdftab_open_json(source, settings);
    if (b == NULL) {
        fprintf(stderr, "open %s: %s\n", source, brdftab_last_error());
        failures++;
        return;
    }
    double wi[3] = {0.0, 0.1, 1.0}, wo[3] = {0.2, 0.0, 1.0};
    float f[3] = {0};
    if (brdftab_channels(b) != 3 || brdftab_eval(b, 1, wi, wo, f) != 0) {
        fprintf(stderr, "eval %s: %s\n", source, brdftab_last_error());
        failures++;
    }
    printf("%s %.9g %.9g %.9g\n", label, f[0], f[1], f[2]);
    printf("%s-flags %u\n", label, brdftab_flags(b));
    brdftab_close(b);
}

int main(int argc, char **argv) {
    if (argc != 2) return 2;
    char table[4096], bsdf[4096];
    snprintf(table, sizeof table, "%s/c.btdb", argv[1]);
    snprintf(bsdf, sizeof bsdf, "%s/c.bsdf", argv[1]);

    if (brdftab_bake(LAMBERT, table, "{\"grid\": \"8x1x8x16\", \"codec\": \"f32\"}") != 0) {
        fprintf(stderr, "bake: %s\n", brdftab_last_error());
        failures++;
    }
    print_normal("table", table, "{\"interp\": \"nearest\"}");
    print_normal("table-default", table, NULL);
    expect_error(brdftab_bake(LAMBERT, table, "{\"gird\": \"small\"}"), "unknown", "gird");
    expect_error(brdftab_bake(LAMBERT, table, "{\"supersample\": 0}"), "bad-value", "supersample");
    expect_error(brdftab_bake(LAMBERT, table, "{not json"), "not-json", "settings");
    expect_error(brdftab_bake(NULL, table, NULL), "null-source", "source");

    if (brdftab_convert(LAMBERT, bsdf,
                        "{\"theta_i\": 4, \"resolution\": 16, \"ndf_resolution\": 32, "
                        "\"pairs\": 0}") != 0) {
        fprintf(stderr, "convert: %s\n", brdftab_last_error());
        failures++;
    }
    print_normal("bsdf", bsdf, "");
    /* A count of accuracy pairs no memory holds: -1 naming `pairs`, before any bake, never
     * an allocation failure that aborts the host (every output kind). */
    expect_error(brdftab_convert(LAMBERT, bsdf, "{\"pairs\": 4611686018427387904}"),
                 "convert-pairs-bsdf", "pairs");
    expect_error(brdftab_convert(LAMBERT, table, "{\"pairs\": 18446744073709551615}"),
                 "convert-pairs-table", "pairs");

    char *fit = brdftab_fit("{\"model\":\"lambert\",\"kd\":0.3}", "lambert",
                            "{\"pairs\": 300, \"starts\": 2}");
    if (fit == NULL) {
        fprintf(stderr, "fit: %s\n", brdftab_last_error());
        failures++;
    } else {
        printf("fit %s\n", fit);
        brdftab_free_string(fit);
    }
    if (brdftab_fit(LAMBERT, "lambert", "{\"strats\": 2}") != NULL) failures++;
    expect_error(-1, "fit-unknown", "strats");
    /* As many fit pairs as memory cannot hold, or whose residual count overflows. */
    if (brdftab_fit(LAMBERT, "lambert", "{\"pairs\": 10000000000}") != NULL) failures++;
    expect_error(-1, "fit-pairs", "pairs");
    if (brdftab_fit(LAMBERT, "lambert", "{\"pairs\": 9223372036854775807}") != NULL) failures++;
    expect_error(-1, "fit-pairs-overflow", "pairs");
    brdftab_free_string(NULL);
    print_normal("lambert", LAMBERT, NULL);
    if (brdftab_flags(NULL) != 0) failures++;

    if (brdftab_open_json(LAMBERT, "{\"interp\": \"cubic\"}") != NULL) failures++;
    expect_error(-1, "open-interp", "interp");
    return failures == 0 ? 0 : 1;
}
