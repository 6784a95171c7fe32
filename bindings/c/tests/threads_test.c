/* Many threads on one handle (driven by tests/c_programs.rs): the header's promise that every
 * call but brdftab_close may run concurrently.
 *
 *   threads_test SOURCE
 * A fresh (lazily decoding) handle is hammered by 8 threads, each starting at another pair so
 * that chunks decode concurrently, with pair-by-pair and batch calls, spectral ones included;
 * every result must equal, bit for bit, what a second handle computed on one thread, and each
 * thread's last error is its own. Prints FAIL lines and exits 1 on a mismatch.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include "brdftab.h"

enum { T = 8, N = 2000, C = 3, K = 4 };
static brdftab_brdf *B;
static int failures[T];
static double WI[3 * N], WO[3 * N], U[2 * N], NM[K] = {400, 480, 560, 640};
static float RF[C * N], RW[C * N], RS[K * N];
static double RWI[3 * N], RP[N], RPDF[N];
static unsigned char RD[N];

static void *work(void *arg) {
    int t = (int)(size_t)arg;
    static _Thread_local double wi[3 * N], p[N], pdf[N];
    static _Thread_local float f[C * N], w[C * N], s[K * N];
    static _Thread_local unsigned char d[N];
    for (int j = 0; j < N; j++) { /* pair by pair, from another start on each thread */
        int k = (j + t * N / T) % N;
        if (brdftab_eval(B, 1, WI + 3 * k, WO + 3 * k, f + C * k) ||
            brdftab_pdf(B, 1, WI + 3 * k, WO + 3 * k, pdf + k) ||
            brdftab_sample_delta(B, 1, WO + 3 * k, U + 2 * k, wi + 3 * k, p + k, w + C * k, d + k))
            failures[t]++;
    }
    if (memcmp(f, RF, sizeof f) || memcmp(pdf, RPDF, sizeof pdf) || memcmp(wi, RWI, sizeof wi) ||
        memcmp(p, RP, sizeof p) || memcmp(w, RW, sizeof w) || memcmp(d, RD, sizeof d))
        failures[t]++;
    if (brdftab_eval_spectral(B, N, WI, WO, K, NM, s) || memcmp(s, RS, sizeof s)) failures[t]++;
    /* This thread's error is its own: a message naming what this thread did wrong. */
    char want[32];
    snprintf(want, sizeof want, "interp %d", 3 + t);
    brdftab_open_options bad = {.interp = 3 + t};
    if (brdftab_open_with("{\"model\": \"lambert\"}", &bad) != NULL ||
        strncmp(brdftab_last_error(), want, strlen(want)) != 0)
        failures[t]++;
    return NULL;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: %s SOURCE\n", argv[0]);
        return 2;
    }
    for (int k = 0; k < N; k++) { /* pairs over the hemisphere */
        double ti = 1.5 * (k % 50) / 50.0, pi = 6.28 * (k / 50) / 40.0;
        double to = 1.5 * (k % 37) / 37.0, po = 6.28 * (k % 41) / 41.0;
        WI[3 * k] = sin(ti) * cos(pi), WI[3 * k + 1] = sin(ti) * sin(pi), WI[3 * k + 2] = cos(ti);
        WO[3 * k] = sin(to) * cos(po), WO[3 * k + 1] = sin(to) * sin(po), WO[3 * k + 2] = cos(to);
        U[2 * k] = (k % 61) / 61.0, U[2 * k + 1] = (k % 59) / 59.0;
    }
    brdftab_brdf *r = brdftab_open(argv[1]);
    B = brdftab_open(argv[1]);
    if (!r || !B || brdftab_channels(r) != C) {
        fprintf(stderr, "FAIL open: %s\n", brdftab_last_error());
        return 1;
    }
    if (brdftab_eval(r, N, WI, WO, RF) || brdftab_pdf(r, N, WI, WO, RPDF) ||
        brdftab_sample_delta(r, N, WO, U, RWI, RP, RW, RD) ||
        brdftab_eval_spectral(r, N, WI, WO, K, NM, RS)) {
        fprintf(stderr, "FAIL reference: %s\n", brdftab_last_error());
        return 1;
    }
    brdftab_close(r);
    pthread_t th[T];
    for (int t = 0; t < T; t++) pthread_create(&th[t], NULL, work, (void *)(size_t)t);
    for (int t = 0; t < T; t++) pthread_join(th[t], NULL);
    int total = 0;
    for (int t = 0; t < T; t++) {
        if (failures[t]) fprintf(stderr, "FAIL thread %d: %d mismatches\n", t, failures[t]);
        total += failures[t];
    }
    brdftab_close(B);
    return total ? 1 : 0;
}
