// pbrt_bxdf.hpp — a pbrt-v4-style BxDF over brdftab (f, Sample_f, PDF, Flags), on the C++
// wrapper. It mirrors pbrt-v4's BxDF interface (src/pbrt/bxdfs.h) with small stand-in types
// so it compiles with g++ alone; in pbrt, replace the stand-ins by pbrt's own Vector3f,
// SampledSpectrum (evaluate at the path's sampled wavelengths with brdftab_eval_spectral and
// brdftab_sample_spectral — a mirror's reflectance at each of them —, or an RGB result through
// an RGBAlbedoSpectrum), BSDFSample and BxDFFlags.
//
// Conventions agree: pbrt's wo (to the viewer) and wi (to the light) are brdftab's wo and wi, in
// the shading frame with z the normal; f() is f_r without the cosine; Sample_f draws wi given wo.
// pbrt-v4's BxDFs are two-sided (MeasuredBxDF, ConductorBxDF, DiffuseBxDF): seen from below
// (wo.z < 0) the surface reflects as from above, mirrored through the tangent plane. brdftab's
// functions are front-side only (f_r = 0, no sample for wo below the horizon), so the adapter
// flips a back-side pair (wo, wi) -> (-wo, -wi) before calling them, as pbrt's MeasuredBxDF does.
#pragma once

#include <array>
#include <cmath>
#include <optional>

#include "brdftab.hpp"

namespace pbrt_like {

using Float = float;

struct Vector3f {
    Float x, y, z;
    Vector3f operator-() const { return {-x, -y, -z}; }
};

/// pbrt's SameHemisphere: both directions on one side of the surface.
inline bool SameHemisphere(Vector3f a, Vector3f b) { return a.z * b.z > 0; }

/// RGB stand-in for pbrt's SampledSpectrum.
struct SampledSpectrum {
    std::array<Float, 3> c{};
    Float operator[](int i) const { return c[i]; }
};

enum class BxDFFlags : unsigned { Unset = 0, Reflection = 1, Diffuse = 4, Glossy = 8, Specular = 16 };
inline BxDFFlags operator|(BxDFFlags a, BxDFFlags b) {
    return BxDFFlags(unsigned(a) | unsigned(b));
}

struct BSDFSample {
    SampledSpectrum f;
    Vector3f wi;
    Float pdf = 0;
    BxDFFlags flags = BxDFFlags::Unset;
};

/// A BxDF whose values come from any brdftab SOURCE (RGB: three channels expected).
class BrdftabBxDF {
public:
    explicit BrdftabBxDF(const brdftab::Brdf &b) : b_(&b) {
        if (b.channels() != 3) throw brdftab::Error("BrdftabBxDF expects an RGB source");
        // pbrt's BxDF for these is a dielectric; this adapter reflects only (front side).
        if (b.flags() & BRDFTAB_TRANSMISSION)
            throw brdftab::Error("BrdftabBxDF reflects only: the source transmits (a refractor)");
    }

    /// pbrt's flags from the lobes the library declares (glossy when it declares none).
    BxDFFlags Flags() const {
        unsigned f = b_->flags();
        BxDFFlags out = BxDFFlags::Reflection;
        if (f & BRDFTAB_DIFFUSE) out = out | BxDFFlags::Diffuse;
        if (f & BRDFTAB_DELTA) out = out | BxDFFlags::Specular;
        if ((f & BRDFTAB_GLOSSY) || !(f & (BRDFTAB_DIFFUSE | BRDFTAB_DELTA)))
            out = out | BxDFFlags::Glossy;
        return out;
    }

    /// The flags of a smooth draw: Flags() without Specular.
    BxDFFlags SmoothFlags() const {
        unsigned f = b_->flags();
        BxDFFlags out = BxDFFlags::Reflection;
        if (f & BRDFTAB_DIFFUSE) out = out | BxDFFlags::Diffuse;
        if ((f & BRDFTAB_GLOSSY) || !(f & BRDFTAB_DIFFUSE)) out = out | BxDFFlags::Glossy;
        return out;
    }

    SampledSpectrum f(Vector3f wo, Vector3f wi) const {
        if (!SameHemisphere(wo, wi)) return {};  // reflection only
        if (wo.z < 0) wo = -wo, wi = -wi;        // two-sided, as pbrt's MeasuredBxDF
        float v[3];
        b_->eval(to(wi), to(wo), v);
        return {{v[0], v[1], v[2]}};
    }

    std::optional<BSDFSample> Sample_f(Vector3f wo, Float /*uc*/, std::array<Float, 2> u) const {
        if (wo.z == 0) return std::nullopt;
        // Two-sided: a back-side wo samples the front's lobe at -wo, and the draw flips back.
        const bool flip = wo.z < 0;
        float w[3];
        brdftab::Sample s = b_->sample(to(flip ? -wo : wo), u[0], u[1], w);
        if (!(s.pdf > 0) || !(s.wi.z > 0)) return std::nullopt;
        Vector3f wi{Float(s.wi.x), Float(s.wi.y), Float(s.wi.z)};
        if (flip) wi = -wi;
        if (s.delta) {
            // pbrt's specular sample: f = weight · pdf / |cos θi|, so that f |cos θi| / pdf is the
            // library's weight (the lobe's reflectance over the probability of choosing it).
            Float k = Float(s.pdf / s.wi.z);
            return BSDFSample{{{w[0] * k, w[1] * k, w[2] * k}}, wi, Float(s.pdf),
                              BxDFFlags::Reflection | BxDFFlags::Specular};
        }
        // A smooth draw: the smooth lobes' flags (a sum's mirror term did not draw it).
        return BSDFSample{f(wo, wi), wi, Float(s.pdf), SmoothFlags()};
    }

    Float PDF(Vector3f wo, Vector3f wi) const {
        if (!SameHemisphere(wo, wi)) return 0;
        if (wo.z < 0) wo = -wo, wi = -wi;
        return Float(b_->pdf(to(wi), to(wo)));
    }

private:
    static brdftab::Vec3 to(Vector3f v) { return {v.x, v.y, v.z}; }
    const brdftab::Brdf *b_;
};

}  // namespace pbrt_like
