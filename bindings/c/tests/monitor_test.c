/* Progress monitors through the C ABI: brdftab_bake_monitored, brdftab_convert_monitored and
 * brdftab_fit_monitored. Usage: monitor_test DIR. Every output it asks for goes in DIR; the
 * stopped ones must leave nothing there (tests/c_programs.rs lists DIR afterwards). Prints what
 * it saw and exits 1 when a call does not do what the header says. */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include "brdftab.h"

static int failures = 0;

#define CHECK(cond, ...)                                  \
    do {                                                  \
        if (!(cond)) {                                    \
            fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__); \
            fprintf(stderr, __VA_ARGS__);                 \
            fprintf(stderr, "\n");                        \
            failures++;                                   \
        }                                                 \
    } while (0)

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* What a monitor saw: it answers 0 at its `stop_at`-th call (1-based; 0 = never). */
typedef struct {
    int stop_at;
    int calls;
    double last;
    int decreasing, out_of_range, other_thread;
    int ones; /* calls with n = 1: one, the last, for a call that succeeded */
    pthread_t caller;
    double stopped_at; /* when it answered 0 */
} Watch;

static int monitor(void *user, double n) {
    Watch *w = (Watch *)user;
    w->calls++;
    if (n < w->last) w->decreasing = 1;
    if (!(n >= 0.0 && n <= 1.0)) w->out_of_range = 1;
    if (!pthread_equal(pthread_self(), w->caller)) w->other_thread = 1;
    w->last = n;
    if (n == 1.0) w->ones++;
    if (w->calls == w->stop_at) {
        w->stopped_at = now();
        return 0;
    }
    return 1;
}

static Watch watch(int stop_at) {
    Watch w;
    memset(&w, 0, sizeof w);
    w.stop_at = stop_at;
    w.caller = pthread_self();
    return w;
}

static void check_watch(const char *what, const Watch *w) {
    CHECK(!w->decreasing, "%s: n decreased", what);
    CHECK(!w->out_of_range, "%s: n outside [0, 1]", what);
    CHECK(!w->other_thread, "%s: the monitor was called from another thread", what);
}

static void check_cancelled(const char *what, int rc, const Watch *w, const char *path) {
    CHECK(rc == -1, "%s: rc %d, wanted -1", what, rc);
    CHECK(strstr(brdftab_last_error(), "cancelled") != NULL, "%s: message \"%s\"", what,
          brdftab_last_error());
    CHECK(access(path, F_OK) != 0, "%s: %s exists", what, path);
    CHECK(w->calls == w->stop_at, "%s: %d calls after the 0 at call %d", what, w->calls,
          w->stop_at);
    check_watch(what, w);
}

static const char *GGX = "{\"model\":\"ggx\",\"alpha\":0.2}";
static const char *WARD = "{\"model\":\"ward\",\"ks\":0.5,\"alpha_x\":0.1,\"alpha_y\":0.3}";

int main(int argc, char **argv) {
    if (argc != 2) return 2;
    char out[4096], db[4096], bsdf[4096], done[4096];
    snprintf(out, sizeof out, "%s/stopped.btdb", argv[1]);
    snprintf(db, sizeof db, "%s/db.btdb", argv[1]);
    snprintf(bsdf, sizeof bsdf, "%s/w.bsdf", argv[1]);
    snprintf(done, sizeof done, "%s/done.btdb", argv[1]);

    /* Stopped at the first call (n = 0, before any work): nothing is read or written. */
    Watch w = watch(1);
    int rc = brdftab_bake_monitored(GGX, out, NULL, monitor, &w);
    check_cancelled("bake-first", rc, &w, out);
    CHECK(w.last == 0.0, "bake-first: n %g", w.last);
    w = watch(1);
    rc = brdftab_convert_monitored(GGX, out, NULL, monitor, &w);
    check_cancelled("convert-first", rc, &w, out);
    w = watch(1);
    char *fit = brdftab_fit_monitored(GGX, "ggx", NULL, monitor, &w);
    check_cancelled("fit-first", fit == NULL ? -1 : 0, &w, out);
    brdftab_free_string(fit);

    /* Stopped at the second call (~50 ms in), while the work runs: an anisotropic source's
     * .bsdf file (15 s to its end) and a conversion to a database table with a long accuracy
     * report. The call returns soon after the 0. */
    w = watch(2);
    rc = brdftab_convert_monitored(WARD, bsdf, NULL, monitor, &w);
    double latency = now() - w.stopped_at;
    check_cancelled("convert-bsdf", rc, &w, bsdf);
    printf("latency convert-bsdf %.3f\n", latency);
    CHECK(latency < 3.0, "convert-bsdf: returned %.3f s after the 0", latency);
    char db_name[4200];
    snprintf(db_name, sizeof db_name, "%s#t", db);
    w = watch(2);
    rc = brdftab_convert_monitored(GGX, db_name, "{\"preset\": \"small\", \"pairs\": 4000000}",
                                   monitor, &w);
    latency = now() - w.stopped_at;
    check_cancelled("convert-db", rc, &w, db);
    printf("latency convert-db %.3f\n", latency);
    CHECK(latency < 3.0, "convert-db: returned %.3f s after the 0", latency);

    /* Never stopped: the result, with n = 1 last; a NULL monitor is the plain call. */
    w = watch(0);
    rc = brdftab_bake_monitored(GGX, done, "{\"preset\": \"small\"}", monitor, &w);
    CHECK(rc == 0, "bake: %s", brdftab_last_error());
    CHECK(w.calls >= 2 && w.last == 1.0, "bake: %d calls, last n %g", w.calls, w.last);
    /* n reached 1 while a bake still ran (a finished stage): 1 only once it succeeded. */
    CHECK(w.ones == 1, "bake: n = 1 in %d calls", w.ones);
    check_watch("bake", &w);
    printf("bake calls %d\n", w.calls);
    w = watch(0);
    fit = brdftab_fit_monitored(GGX, "ggx", "{\"pairs\": 300, \"starts\": 2}", monitor, &w);
    CHECK(fit != NULL && strstr(fit, "\"spec\"") != NULL, "fit: %s",
          fit ? fit : brdftab_last_error());
    CHECK(w.last == 1.0 && w.ones == 1, "fit: last n %g, n = 1 in %d calls", w.last, w.ones);
    check_watch("fit", &w);
    brdftab_free_string(fit);
    rc = brdftab_bake_monitored(GGX, done, "{\"preset\": \"small\", \"gird\": 1}", NULL, NULL);
    CHECK(rc == -1 && strstr(brdftab_last_error(), "gird") != NULL, "null monitor: %s",
          brdftab_last_error());
    return failures == 0 ? 0 : 1;
}
