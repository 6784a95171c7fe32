//! What a model declares about itself: its symmetries, whether it is a delta or transmits
//! ([`Flags`]), and the kinds of lobe it has ([`Lobes`]).

use serde::Serialize;

/// What a model declares about itself. Tables use these to choose symmetry reductions (after
/// verifying them); analysis reports compare them with what is measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct Flags {
    /// Reflection only along a single direction (a Dirac delta): `eval` returns 0 and
    /// [`Brdf::sample`](super::Brdf::sample) returns the direction and its weight.
    pub delta: bool,
    /// Helmholtz reciprocity: f(wi, wo) = f(wo, wi).
    pub reciprocal: bool,
    /// Invariant under a common rotation of both directions about the normal.
    pub isotropic: bool,
    /// Bilateral (mirror) symmetry about the plane of incidence: f is unchanged when both
    /// directions are reflected through the x–z plane (for isotropic models: when φo − φi flips sign).
    pub bilateral: bool,
    /// Transmits light to the other side of the surface (refraction).
    pub transmission: bool,
    /// The kinds of lobe the BRDF has, for hosts to map to their own flags (Mitsuba's
    /// `DiffuseReflection`/`GlossyReflection`/`DeltaReflection`, pbrt-v4's `BxDFFlags`).
    pub lobes: Lobes,
}

/// The kinds of lobe a BRDF has; a sum has the union of its terms'. Tables and measured data
/// are glossy (whatever they hold, a renderer must sample them as such).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct Lobes {
    /// A constant or slowly varying lobe (Lambert, Oren-Nayar): cosine sampling is near ideal.
    pub diffuse: bool,
    /// A lobe with a peak (the Phong family, microfacet models, tables, measurements).
    pub glossy: bool,
    /// A Dirac delta (ideal mirror, ideal refraction): `eval` cannot see it.
    pub delta: bool,
}

impl Lobes {
    /// Diffuse only.
    pub const DIFFUSE: Lobes = Lobes {
        diffuse: true,
        glossy: false,
        delta: false,
    };
    /// Glossy only.
    pub const GLOSSY: Lobes = Lobes {
        diffuse: false,
        glossy: true,
        delta: false,
    };
    /// Delta only.
    pub const DELTA: Lobes = Lobes {
        diffuse: false,
        glossy: false,
        delta: true,
    };

    /// The lobes of either.
    pub fn union(self, o: Lobes) -> Lobes {
        Lobes {
            diffuse: self.diffuse || o.diffuse,
            glossy: self.glossy || o.glossy,
            delta: self.delta || o.delta,
        }
    }
}

impl Flags {
    /// Flags of a smooth, reciprocal, isotropic, bilaterally symmetric glossy reflection model
    /// — the common case.
    pub const SMOOTH_SYMMETRIC: Flags = Flags {
        delta: false,
        reciprocal: true,
        isotropic: true,
        bilateral: true,
        transmission: false,
        lobes: Lobes::GLOSSY,
    };
}
