// brdftab.hpp — a header-only C++17 wrapper of brdftab.h: an RAII handle, span-style batch
// calls over contiguous arrays, and exceptions that carry the library's message.
//
//   #include "brdftab.hpp"
//   brdftab::Brdf b("materials.btdb#gold");
//   std::vector<brdftab::Vec3> wi(n), wo(n);         // the C ABI's n x 3 doubles
//   std::vector<float> f(n * b.channels());
//   b.eval(n, wi.data(), wo.data(), f.data());
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "brdftab.h"

namespace brdftab {

/// A failure of the library, with its message.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string &what) : std::runtime_error(what) {}
};

namespace detail {
inline void check(int rc) {
    if (rc != 0) throw Error(brdftab_last_error());
}
}  // namespace detail

/// A 3-vector in the local frame (z = normal), laid out as the C ABI's double[3].
struct Vec3 {
    double x, y, z;
};
static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");

namespace detail {
/// An array of Vec3 as the C ABI's doubles. Not `&v->x`: that is a member access through a null
/// pointer (undefined) for an empty std::vector's data(), which an empty batch passes.
inline const double *xyz(const Vec3 *v) { return reinterpret_cast<const double *>(v); }
inline double *xyz(Vec3 *v) { return reinterpret_cast<double *>(v); }
}  // namespace detail

/// One sample of Brdf::sample. `delta`: drawn from a delta lobe (a mirror, or a sum's mirror
/// term): `pdf` is then the probability of choosing that lobe, and the weight its reflectance
/// over it.
struct Sample {
    Vec3 wi;
    double pdf;
    bool delta;
};

/// An open BRDF (move-only). Its const methods may be called from several threads at once.
class Brdf {
public:
    /// Opens any SOURCE (spec JSON, .json, table, DB#NAME, MERL .binary, RGL .bsdf).
    explicit Brdf(const std::string &source) : h_(brdftab_open(source.c_str())) {
        if (!h_) throw Error(brdftab_last_error());
    }
    /// Opens with options (interpolation, wavelengths, eager decoding).
    Brdf(const std::string &source, const brdftab_open_options &opts)
        : h_(brdftab_open_with(source.c_str(), &opts)) {
        if (!h_) throw Error(brdftab_last_error());
    }
    Brdf(const Brdf &) = delete;
    Brdf &operator=(const Brdf &) = delete;
    Brdf(Brdf &&o) noexcept : h_(std::exchange(o.h_, nullptr)) {}
    Brdf &operator=(Brdf &&o) noexcept {
        if (this != &o) {
            brdftab_close(h_);
            h_ = std::exchange(o.h_, nullptr);
        }
        return *this;
    }
    ~Brdf() { brdftab_close(h_); }

    /// Channels per value (3 for RGB).
    std::size_t channels() const { return brdftab_channels(h_); }
    /// What the BRDF declares: a bit set of BRDFTAB_DIFFUSE, _GLOSSY, _DELTA, ... (brdftab.h).
    unsigned flags() const { return brdftab_flags(h_); }
    /// Channel names ("R", "G", "B" or "550nm", ...).
    std::vector<std::string> channel_names() const {
        std::vector<std::string> v;
        for (std::size_t i = 0; i < channels(); ++i) v.emplace_back(brdftab_channel_name(h_, i));
        return v;
    }

    /// f_r (no cosine) for n pairs; f holds n * channels() floats.
    void eval(std::size_t n, const Vec3 *wi, const Vec3 *wo, float *f) const {
        detail::check(brdftab_eval(h_, n, detail::xyz(wi), detail::xyz(wo), f));
    }
    /// f_r for one pair into f[channels()].
    void eval(const Vec3 &wi, const Vec3 &wo, float *f) const { eval(1, &wi, &wo, f); }
    /// pdf(wi | wo) for n pairs.
    void pdf(std::size_t n, const Vec3 *wi, const Vec3 *wo, double *p) const {
        detail::check(brdftab_pdf(h_, n, detail::xyz(wi), detail::xyz(wo), p));
    }
    double pdf(const Vec3 &wi, const Vec3 &wo) const {
        double p = 0.0;
        pdf(1, &wi, &wo, &p);
        return p;
    }
    /// Draws wi for n given wo from u (n x 2 in [0,1)^2); weight = f cos(theta_i) / pdf.
    void sample(std::size_t n, const Vec3 *wo, const double *u, Vec3 *wi, double *p,
                float *weight) const {
        detail::check(brdftab_sample(h_, n, detail::xyz(wo), u, detail::xyz(wi), p, weight));
    }
    /// The same with each draw's delta flag (delta: n bytes, 1 for a delta lobe's draw).
    void sample(std::size_t n, const Vec3 *wo, const double *u, Vec3 *wi, double *p,
                float *weight, unsigned char *delta) const {
        detail::check(brdftab_sample_delta(h_, n, detail::xyz(wo), u, detail::xyz(wi), p, weight,
                                                 delta));
    }
    Sample sample(const Vec3 &wo, double u0, double u1, float *weight) const {
        double u[2] = {u0, u1};
        Sample s{};
        unsigned char d = 0;
        sample(1, &wo, u, &s.wi, &s.pdf, weight, &d);
        s.delta = d != 0;
        return s;
    }
    /// Directional albedo at incidence theta and azimuth phi (radians, phi from the local x
    /// axis), one value per channel.
    std::vector<double> albedo(double theta, double phi = 0.0) const {
        std::vector<double> a(channels());
        detail::check(brdftab_albedo_at(h_, theta, phi, a.data()));
        return a;
    }
    /// The C handle, for calls the wrapper does not cover.
    const brdftab_brdf *get() const { return h_; }

private:
    brdftab_brdf *h_;
};

}  // namespace brdftab
