/* A MERL-style nearest lookup in C: the baseline of `examples/merl_c_compare.rs`.
 *
 * Written for brdftab from the MERL database's published conventions (Matusik et al. 2003):
 * the file is three int32 dimensions (90, 90, 180) and then 3 x 1 458 000 doubles, red, green,
 * blue, each cell (θh index, θd index, φd index) with θh indexed by sqrt(θh / 90°) · 90, θd by
 * θd / 90° · 90, φd folded by reciprocity onto [0, π) by φd / π · 180, and the channels scaled
 * by 1/1500, 1.15/1500 and 1.66/1500. A lookup takes two unit vectors (as a renderer has them),
 * computes the half and difference angles with acos and atan2, as the reference reader does,
 * and reads the nearest cell.
 *
 * Usage: merl_nearest FILE.binary [PAIRS] — prints "ns_per_lookup checksum" (wall time of the
 * lookup loop on one thread). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define NTH 90
#define NTD 90
#define NPD 180

static double *data;

static int theta_h_index(double th) {
    if (th <= 0.0) return 0;
    int i = (int)(sqrt(th / (M_PI / 2)) * NTH);
    return i < 0 ? 0 : (i >= NTH ? NTH - 1 : i);
}

static int theta_d_index(double td) {
    int i = (int)(td / (M_PI / 2) * NTD);
    return i < 0 ? 0 : (i >= NTD ? NTD - 1 : i);
}

static int phi_d_index(double pd) {
    if (pd < 0.0) pd += M_PI;
    int i = (int)(pd / M_PI * NPD);
    return i < 0 ? 0 : (i >= NPD ? NPD - 1 : i);
}

/* Rotates v about axis (0,0,1) (z) or (0,1,0) (y) by angle a. */
static void rot_z(double v[3], double a) {
    double c = cos(a), s = sin(a), x = v[0] * c - v[1] * s, y = v[0] * s + v[1] * c;
    v[0] = x;
    v[1] = y;
}

static void rot_y(double v[3], double a) {
    double c = cos(a), s = sin(a), x = v[0] * c + v[2] * s, z = -v[0] * s + v[2] * c;
    v[0] = x;
    v[2] = z;
}

static void lookup(const double wi[3], const double wo[3], double out[3]) {
    double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
    double n = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    h[0] /= n;
    h[1] /= n;
    h[2] /= n;
    double th = acos(h[2] > 1.0 ? 1.0 : h[2]), ph = atan2(h[1], h[0]);
    double d[3] = {wi[0], wi[1], wi[2]};
    rot_z(d, -ph);
    rot_y(d, -th);
    double td = acos(d[2] > 1.0 ? 1.0 : (d[2] < -1.0 ? -1.0 : d[2])), pd = atan2(d[1], d[0]);
    size_t k = ((size_t)theta_h_index(th) * NTD + theta_d_index(td)) * NPD + phi_d_index(pd);
    size_t N = (size_t)NTH * NTD * NPD;
    out[0] = data[k] * (1.0 / 1500.0);
    out[1] = data[k + N] * (1.15 / 1500.0);
    out[2] = data[k + 2 * N] * (1.66 / 1500.0);
}

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static double uniform(void) {
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) * (1.0 / 9007199254740992.0);
}

/* Uniform on the upper hemisphere. */
static void hemisphere(double w[3]) {
    double z = uniform(), p = 2 * M_PI * uniform(), s = sqrt(fmax(0.0, 1 - z * z));
    w[0] = s * cos(p);
    w[1] = s * sin(p);
    w[2] = z;
}

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: %s FILE.binary [PAIRS]\n", argv[0]);
        return 2;
    }
    long pairs = argc > 2 ? atol(argv[2]) : 1000000;
    FILE *f = fopen(argv[1], "rb");
    if (!f) {
        perror(argv[1]);
        return 1;
    }
    int32_t dims[3];
    size_t N = (size_t)NTH * NTD * NPD;
    if (fread(dims, 4, 3, f) != 3 || (size_t)dims[0] * dims[1] * dims[2] != N) {
        fprintf(stderr, "%s: not a MERL file\n", argv[1]);
        return 1;
    }
    data = malloc(3 * N * sizeof(double));
    if (!data || fread(data, sizeof(double), 3 * N, f) != 3 * N) {
        fprintf(stderr, "%s: short file\n", argv[1]);
        return 1;
    }
    fclose(f);
    double *dirs = malloc(6 * (size_t)pairs * sizeof(double));
    double *out = malloc(3 * (size_t)pairs * sizeof(double));
    if (!dirs || !out) return 1;
    for (long i = 0; i < pairs; i++) {
        hemisphere(dirs + 6 * i);
        hemisphere(dirs + 6 * i + 3);
    }
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    for (long i = 0; i < pairs; i++) lookup(dirs + 6 * i, dirs + 6 * i + 3, out + 3 * i);
    clock_gettime(CLOCK_MONOTONIC, &b);
    double ns = ((b.tv_sec - a.tv_sec) * 1e9 + (b.tv_nsec - a.tv_nsec)) / pairs;
    double sum = 0;
    for (long i = 0; i < 3 * pairs; i++) sum += out[i];
    printf("%.2f %.6g\n", ns, sum);
    return 0;
}
