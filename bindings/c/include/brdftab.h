/*
 * brdftab.h — the C ABI of brdftab (tabulated BRDFs: analytic models, dense compressed tables,
 * MERL and RGL-EPFL measured data).
 *
 * Link: -lbrdftab_c (libbrdftab_c.so or libbrdftab_c.a; the static library also needs
 * -lpthread -ldl -lm), or `pkg-config --cflags --libs brdftab`.
 *
 * Conventions (those of the Rust `Brdf` trait):
 *   - local shading frame, z is the normal; wi (to the light) and wo (to the viewer) both point
 *     away from the surface; directions need not be normalized (any finite nonzero length,
 *     1e-300 and 1e308 included); float directions normalized in float (unit to float
 *     rounding) and widened to double cost no more than exact ones; below the horizon f_r = 0;
 *   - brdftab_eval returns f_r in 1/sr, NOT multiplied by a cosine;
 *   - brdftab_sample draws wi for a given wo; weight = f_r * cos(theta_i) / pdf;
 *   - arrays are pair-major: wi, wo are n x 3 doubles (x, y, z), u is n x 2, f and weight are
 *     n x channels floats; an output array must not overlap an input or another output (no
 *     sampling wi in place over wo: copy wo first).
 * Every int-returning function returns 0 on success and -1 on failure, with the reason in
 * brdftab_last_error() (per thread). n = 0 succeeds whatever the pointers; a NULL handle or
 * array with n > 0 fails, and so does an n whose arrays would exceed PTRDIFF_MAX bytes (or
 * whose n x channels overflows size_t). No call aborts the process or prints on stderr on bad
 * input (an internal panic is caught, reported as -1 and printed nowhere).
 *
 * Corrupt tables: a table opened lazily (the default) decodes each chunk on the first lookup
 * that needs it. A chunk that fails its checksum leaves the handle failed for good: the eval,
 * pdf, sample or albedo call that met it, and every later one on that handle, returns -1 with
 * the checksum error; the values that call wrote are not to be used. Open with eager = 1 to
 * check every chunk up front instead (brdftab_open_with then returns NULL).
 *
 * NaN: a direction with a NaN or infinite component, or a zero vector, is not an error: f_r and
 * pdf are 0 for it and sample gives wi = 0, pdf = 0, weight = 0 (as the library does); a NaN
 * in u, or a u outside [0, 1), gives no sample either. A theta outside [0, pi/2) in brdftab_albedo (NaN included) is an
 * error (-1). A direction a hair above the horizon is a direction: where a lobe grows like
 * 1/cos theta (Ward, measured RGL data) its f_r or sample weight there can be huge, FLT_MAX or
 * +inf (for cos theta_o below about 1e-38), never NaN or negative: clamp a path's throughput
 * if such directions reach these calls.
 * Thread safety: every call on a handle (eval, pdf, the sample and spectral calls, albedo,
 * channels, flags, channel_name) may run concurrently from any number of threads; only
 * brdftab_close must not overlap another call on that handle.
 */
#ifndef BRDFTAB_H
#define BRDFTAB_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* An open BRDF (opaque). */
typedef struct brdftab_brdf brdftab_brdf;

/* Options of brdftab_open_with; zero-initialized means the defaults.
 * The struct may grow in later versions without breaking programs built against this header:
 * `size` is sizeof(brdftab_open_options) as the program's header defines it, or 0 for this
 * first layout (so a zero-initialized struct stays valid in every version, any later field at
 * its default). A library older than the program's header accepts the larger struct when the
 * fields it does not know are all zero, and fails the open otherwise. */
typedef struct brdftab_open_options {
    size_t size;              /* sizeof(brdftab_open_options), or 0 for this first layout */
    int interp;               /* tables and MERL files: 0 auto (default: nearest on MERL
                                 cells, linear otherwise), 1 nearest, 2 linear */
    size_t n_wavelengths;     /* 0 keeps the source's channels */
    const double *wavelengths; /* nm, strictly increasing (model specs, RGL files) */
    int eager;                /* non-zero: decode every table chunk at open */
} brdftab_open_options;

/* Opens any SOURCE the brdftab CLI takes: a model spec as JSON text or a .json file, a table
 * file, DB#NAME (a table of a database), a MERL .binary, an RGL .bsdf. NULL on failure. A
 * path's bytes are taken as they are (on Unix a file name need not be UTF-8; JSON text must
 * be), here and in every SOURCE argument below. */
brdftab_brdf *brdftab_open(const char *source);
/* The same with options (opts NULL = defaults). */
brdftab_brdf *brdftab_open_with(const char *source, const brdftab_open_options *opts);
/* This thread's last failure, "" if none; valid until this thread's next brdftab call. Calls
 * from exit handlers (atexit, C++ static destructors, thread-exit destructors) work, but after
 * the thread's storage is destroyed no message is kept: this returns a fixed note saying so. */
const char *brdftab_last_error(void);
/* Closes a handle; NULL is a no-op. */
void brdftab_close(brdftab_brdf *b);
/* Number of channels (3 for RGB); 0 for NULL. */
size_t brdftab_channels(const brdftab_brdf *b);
/* What the BRDF declares, a bit set of the BRDFTAB_* values below (0 for NULL): the kinds of
 * lobe it has (a renderer maps them to its own flags) and its symmetries. */
#define BRDFTAB_DIFFUSE 1u
#define BRDFTAB_GLOSSY 2u
#define BRDFTAB_DELTA 4u
#define BRDFTAB_TRANSMISSION 8u
#define BRDFTAB_RECIPROCAL 16u
#define BRDFTAB_ISOTROPIC 32u
#define BRDFTAB_BILATERAL 64u
unsigned brdftab_flags(const brdftab_brdf *b);
/* Name of channel i ("R", "G", "B" or e.g. "550nm"); NULL if out of range. Valid while open. */
const char *brdftab_channel_name(const brdftab_brdf *b, size_t i);
/* f_r for n pairs into f (n x channels). */
int brdftab_eval(const brdftab_brdf *b, size_t n, const double *wi, const double *wo, float *f);
/* pdf(wi | wo) of brdftab_sample for n pairs. */
int brdftab_pdf(const brdftab_brdf *b, size_t n, const double *wi, const double *wo, double *pdf);
/* Both of the same n pairs in one call (multiple importance sampling): f (n x channels) as
 * brdftab_eval, pdf (n) as brdftab_pdf; f and pdf must not overlap. */
int brdftab_eval_pdf(const brdftab_brdf *b, size_t n, const double *wi, const double *wo,
                     float *f, double *pdf);
/* Draws wi for each wo from u in [0,1)^2: wi (n x 3), pdf (n), weight (n x channels). A pair
 * with no sample gets wi = 0, pdf = 0, weight = 0. */
int brdftab_sample(const brdftab_brdf *b, size_t n, const double *wo, const double *u,
                   double *wi, double *pdf, float *weight);
/* brdftab_sample, and delta[k] = 1 where pair k drew a delta lobe (a mirror, or a sum's mirror
 * term: its pdf is then the probability of choosing that lobe, not a density, brdftab_pdf does
 * not contain it, and its weight is the lobe's reflectance over that probability), else 0. A
 * renderer gives such draws its specular path (no MIS with light sampling). delta: n bytes. */
int brdftab_sample_delta(const brdftab_brdf *b, size_t n, const double *wo, const double *u,
                         double *wi, double *pdf, float *weight, unsigned char *delta);
/* f_r of n pairs at the k wavelengths nm (the same for every pair, each a finite number of nm
 * > 0) into f (n x k): the source's own spectral data where it has them (models, spectral RGL
 * files), its channels otherwise (wavelength channels interpolated; RGB through a
 * colour-preserving basis: the spectrum's CIE 1931 / D65 sRGB is the source's RGB). For
 * renderers that draw their wavelengths per path (pbrt-v4). Tables, MERL and RGL files look
 * each pair up once for all k wavelengths. With k = 0, nm and f may be NULL. */
int brdftab_eval_spectral(const brdftab_brdf *b, size_t n, const double *wi, const double *wo,
                          size_t k, const double *nm, float *f);
/* brdftab_sample_delta with the weights at the k wavelengths nm (weight: n x k), a mirror's
 * reflectance at each of them for its draws. With k = 0, nm and weight may be NULL (wi, pdf and
 * delta are still drawn). */
int brdftab_sample_spectral(const brdftab_brdf *b, size_t n, const double *wo, const double *u,
                            size_t k, const double *nm, double *wi, double *pdf, float *weight,
                            unsigned char *delta);
/* Directional albedo for light at polar angle theta in [0, pi/2) (radians, light above the
 * horizon; anything else, pi/2 included, is an error, -1): one double per channel (a closed
 * form where the model has one, else adaptive quadrature: 1e-6 relative for models, 1e-4 for
 * tables and measured data). */
int brdftab_albedo(const brdftab_brdf *b, double theta, double *albedo);
/* The same for light at azimuth phi (radians, from the local x axis, alpha_x's direction;
 * brdftab_albedo is phi = 0): an anisotropic source's albedo depends on it. A non-finite phi
 * is -1. */
int brdftab_albedo_at(const brdftab_brdf *b, double theta, double phi, double *albedo);
/* The request layer: settings as a JSON object with the field names of the CLI's flags and
 * Python's keywords (e.g. {"target_error": 0.005, "codec": "f16"}); NULL or "" = defaults; an
 * unknown field is an error. */
/* Opens SOURCE with {"interp": "auto"|"nearest"|"linear", "wavelengths": [..], "eager": bool}. */
brdftab_brdf *brdftab_open_json(const char *source, const char *settings_json);
/* Bakes SOURCE into OUTPUT like `brdftab bake`: DB#NAME is a table of that database, any other
 * name a brdftab (.btdb) file. OUTPUT's bytes, like SOURCE's, need not be UTF-8. 0 or -1. */
int brdftab_bake(const char *source, const char *output, const char *settings_json);
/* Converts SOURCE into OUTPUT (.bsdf, MERL .binary, DB#NAME, .btdb, raw table, by its name)
 * like `brdftab convert`. 0 or -1. */
int brdftab_convert(const char *source, const char *output, const char *settings_json);
/* Fits MODEL ("ggx", "lambert+ggx" or a JSON spec) to SOURCE; the result as JSON (as
 * `brdftab fit --json`), freed with brdftab_free_string; NULL on failure. */
char *brdftab_fit(const char *source, const char *model, const char *settings_json);
/* A progress monitor for the long calls below (as Open Image Denoise's
 * oidnSetFilterProgressMonitorFunction): called with the host's user pointer and n, the
 * fraction done in [0, 1], non-decreasing (the furthest any stage of the operation has got: an
 * indication for a bar, not a time estimate); return nonzero to go on, 0 to stop.
 *   - It is called only on the thread that made the call, never concurrently: the host's
 *     monitor need not be thread-safe (the work runs on other threads meanwhile).
 *   - First with n = 0 before any work (0 there stops before anything is read or written),
 *     then about every 50 ms while the work runs (n at most 0.999 then), and once with n = 1
 *     when it succeeded (its answer then ignored); after it returned 0, not again.
 *   - A stopped call returns -1 (NULL for a fit) with "cancelled" in brdftab_last_error(),
 *     within about 0.3 s of the 0, and writes nothing: OUTPUT (a file, a database's table)
 *     is left as it was, and no temporary file stays. An operation that finishes before it
 *     sees the request returns its result as if it had not been stopped.
 *   - It must return: a monitor that longjmps or throws out of the call leaves the library's
 *     threads working on memory that is gone (undefined behaviour, the host's to avoid).
 * A NULL monitor makes each call the one without _monitored. */
typedef int (*brdftab_progress_fn)(void *user, double n);
/* brdftab_bake, brdftab_convert and brdftab_fit reporting to `progress` with `user`, and
 * stopped when it returns 0 (above). */
int brdftab_bake_monitored(const char *source, const char *output, const char *settings_json,
                           brdftab_progress_fn progress, void *user);
int brdftab_convert_monitored(const char *source, const char *output, const char *settings_json,
                              brdftab_progress_fn progress, void *user);
char *brdftab_fit_monitored(const char *source, const char *model, const char *settings_json,
                            brdftab_progress_fn progress, void *user);
/* Frees a string returned by brdftab; NULL is a no-op. */
void brdftab_free_string(char *s);
/* The version of the library, e.g. "0.1.0" (static). */
const char *brdftab_version(void);
/* The version of this header (the crate's, as brdftab_version() and brdftab.pc): for
 * compile-time checks (#if BRDFTAB_VERSION_MINOR >= 2) and for comparing against
 * brdftab_version() at run time, where a program built against one header may load another
 * library. */
#define BRDFTAB_VERSION_MAJOR 0
#define BRDFTAB_VERSION_MINOR 1
#define BRDFTAB_VERSION_PATCH 0
#define BRDFTAB_VERSION "0.1.0"

#ifdef __cplusplus
}
#endif

#endif /* BRDFTAB_H */
