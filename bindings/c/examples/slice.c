/* Prints a MERL-style θh × θd slice (φd = 90°) of channel 0 of any SOURCE through the C ABI.
 *
 *   cc -O2 slice.c -I../include -L../../../target/release -lbrdftab_c -lm -o slice
 *   LD_LIBRARY_PATH=../../../target/release ./slice table.btdb [steps]
 *
 * Rows are θd = 0..85°, columns θh = 0..85°, values f_r in 1/sr.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "brdftab.h"

#define BRDFTAB_PI 3.14159265358979323846

/* wi, wo from half/difference angles (Rusinkiewicz 1998) with φh = 0. */
static void halfdiff(double th, double td, double pd, double wi[3], double wo[3]) {
    double d[3] = {sin(td) * cos(pd), sin(td) * sin(pd), cos(td)};
    /* rotate d by θh about y */
    wi[0] = cos(th) * d[0] + sin(th) * d[2];
    wi[1] = d[1];
    wi[2] = -sin(th) * d[0] + cos(th) * d[2];
    double h[3] = {sin(th), 0.0, cos(th)};
    double hd = h[0] * wi[0] + h[1] * wi[1] + h[2] * wi[2];
    for (int k = 0; k < 3; k++) wo[k] = 2.0 * hd * h[k] - wi[k];
}

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: %s SOURCE [steps]\n", argv[0]);
        return 2;
    }
    int steps = argc > 2 ? atoi(argv[2]) : 10;
    if (steps < 1 || steps > 1000) steps = 10;
    brdftab_brdf *b = brdftab_open(argv[1]);
    if (!b) {
        fprintf(stderr, "error: %s\n", brdftab_last_error());
        return 1;
    }
    size_t c = brdftab_channels(b);
    size_t n = (size_t)steps * (size_t)steps;
    double *wi = malloc(n * 3 * sizeof(double)), *wo = malloc(n * 3 * sizeof(double));
    float *f = malloc(n * c * sizeof(float));
    const double deg = BRDFTAB_PI / 180.0, span = 85.0 * deg;
    for (int r = 0; r < steps; r++)
        for (int q = 0; q < steps; q++) {
            size_t k = (size_t)r * steps + q;
            double th = steps > 1 ? span * q / (steps - 1) : 0.0;
            double td = steps > 1 ? span * r / (steps - 1) : 0.0;
            halfdiff(th, td, 90.0 * deg, &wi[3 * k], &wo[3 * k]);
        }
    if (brdftab_eval(b, n, wi, wo, f) != 0) {
        fprintf(stderr, "error: %s\n", brdftab_last_error());
        return 1;
    }
    printf("# channel %s, rows θd 0..85°, columns θh 0..85°, φd = 90°\n",
           brdftab_channel_name(b, 0));
    for (int r = 0; r < steps; r++) {
        for (int q = 0; q < steps; q++) printf("%s%.6g", q ? " " : "", f[((size_t)r * steps + q) * c]);
        printf("\n");
    }
    free(wi);
    free(wo);
    free(f);
    brdftab_close(b);
    return 0;
}
