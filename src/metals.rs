//! Named metals: spectral complex refractive indices n + kj from published measurements.
//!
//! A conductor's Fresnel reflectance needs its complex index n + kj at every wavelength; these
//! tables give it for the four metals most used in rendering, so a spec can say
//! `{"fresnel": {"conductor": "Au"}}` instead of typing numbers. Names are accepted
//! case-insensitively, as chemical symbols (`Au`, `Ag`, `Cu`, `Al`) or English names
//! (`gold`, `silver`, `copper`, `aluminium`/`aluminum`).
//!
//! Sources (the numbers are the published ones, rows between ≈300 and ≈890 nm so that the visible
//! range 380–780 nm is covered with a sample beyond each end; values between rows are linearly
//! interpolated by [`Value::at`], constant outside):
//!
//! - **Au, Ag, Cu**: P. B. Johnson and R. W. Christy, "Optical constants of the noble metals",
//!   *Phys. Rev. B* 6, 4370–4379 (1972), doi:10.1103/PhysRevB.6.4370, room temperature. The paper
//!   tabulates at photon energies; the wavelengths here are λ = hc/E as listed by the
//!   refractiveindex.info database (`main/Au/Johnson.yml`, ...), rounded to 0.1 nm.
//! - **Al**: A. D. Rakić, "Algorithm for the determination of intrinsic optical constants of metal
//!   films: application to aluminum", *Appl. Opt.* 34, 4755–4767 (1995), doi:10.1364/AO.34.004755
//!   (as listed by refractiveindex.info, `main/Al/Rakic.yml`).

use crate::spectrum::Value;

/// Names of the metals [`metal`] knows (chemical symbols; matching is case-insensitive).
pub const NAMES: &[&str] = &["Au", "Ag", "Cu", "Al"];

/// Gold, Johnson & Christy (1972): (λ nm, n, k).
const AU: &[(f64, f64, f64)] = &[
    (300.9, 1.53, 1.889),
    (310.7, 1.53, 1.893),
    (320.4, 1.54, 1.898),
    (331.5, 1.48, 1.883),
    (342.5, 1.48, 1.871),
    (354.2, 1.50, 1.866),
    (367.9, 1.48, 1.895),
    (381.5, 1.46, 1.933),
    (397.4, 1.47, 1.952),
    (413.3, 1.46, 1.958),
    (430.5, 1.45, 1.948),
    (450.9, 1.38, 1.914),
    (471.4, 1.31, 1.849),
    (495.9, 1.04, 1.833),
    (520.9, 0.62, 2.081),
    (548.6, 0.43, 2.455),
    (582.1, 0.29, 2.863),
    (616.8, 0.21, 3.272),
    (659.5, 0.14, 3.697),
    (704.5, 0.13, 4.103),
    (756.0, 0.14, 4.542),
    (821.1, 0.16, 5.083),
    (892.0, 0.17, 5.663),
];

/// Silver, Johnson & Christy (1972): (λ nm, n, k).
const AG: &[(f64, f64, f64)] = &[
    (300.9, 1.34, 0.964),
    (310.7, 1.13, 0.616),
    (320.4, 0.81, 0.392),
    (331.5, 0.17, 0.829),
    (342.5, 0.14, 1.142),
    (354.2, 0.10, 1.419),
    (367.9, 0.07, 1.657),
    (381.5, 0.05, 1.864),
    (397.4, 0.05, 2.070),
    (413.3, 0.05, 2.275),
    (430.5, 0.04, 2.462),
    (450.9, 0.04, 2.657),
    (471.4, 0.05, 2.869),
    (495.9, 0.05, 3.093),
    (520.9, 0.05, 3.324),
    (548.6, 0.06, 3.586),
    (582.1, 0.05, 3.858),
    (616.8, 0.06, 4.152),
    (659.5, 0.05, 4.483),
    (704.5, 0.04, 4.838),
    (756.0, 0.03, 5.242),
    (821.1, 0.04, 5.727),
    (892.0, 0.04, 6.312),
];

/// Copper, Johnson & Christy (1972): (λ nm, n, k).
const CU: &[(f64, f64, f64)] = &[
    (300.9, 1.40, 1.679),
    (310.7, 1.38, 1.729),
    (320.4, 1.38, 1.783),
    (331.5, 1.34, 1.821),
    (342.5, 1.36, 1.864),
    (354.2, 1.37, 1.916),
    (367.9, 1.36, 1.975),
    (381.5, 1.33, 2.045),
    (397.4, 1.32, 2.116),
    (413.3, 1.28, 2.207),
    (430.5, 1.25, 2.305),
    (450.9, 1.24, 2.397),
    (471.4, 1.25, 2.483),
    (495.9, 1.22, 2.564),
    (520.9, 1.18, 2.608),
    (548.6, 1.02, 2.577),
    (582.1, 0.70, 2.704),
    (616.8, 0.30, 3.205),
    (659.5, 0.22, 3.747),
    (704.5, 0.21, 4.205),
    (756.0, 0.24, 4.665),
    (821.1, 0.26, 5.180),
    (892.0, 0.30, 5.768),
];

/// Aluminium, Rakić (1995): (λ nm, n, k).
const AL: &[(f64, f64, f64)] = &[
    (309.96, 0.28003, 3.7081),
    (326.28, 0.31474, 3.9165),
    (364.66, 0.39877, 4.3957),
    (413.28, 0.52135, 5.0008),
    (442.80, 0.60790, 5.3676),
    (476.87, 0.72780, 5.7781),
    (516.60, 0.87340, 6.2418),
    (563.57, 1.0728, 6.7839),
    (619.93, 1.3660, 7.4052),
    (652.25, 1.5724, 7.7354),
    (688.81, 1.8301, 8.0601),
    (729.32, 2.1606, 8.3565),
    (774.91, 2.6154, 8.4914),
    (794.78, 2.7675, 8.3866),
    (815.69, 2.7668, 8.2573),
    (837.74, 2.6945, 8.1878),
    (885.61, 2.2802, 8.1134),
];

/// The table of a metal name (case-insensitive symbol or English name).
fn table(name: &str) -> Option<&'static [(f64, f64, f64)]> {
    let lower = name.trim().to_ascii_lowercase();
    Some(match lower.as_str() {
        "au" | "gold" => AU,
        "ag" | "silver" => AG,
        "cu" | "copper" => CU,
        "al" | "aluminium" | "aluminum" => AL,
        _ => return None,
    })
}

/// The spectral (n, k) of a named metal as sampled spectra, or `None` for an unknown name.
///
/// ```
/// let (n, k) = brdftab::metals::metal("au").unwrap();
/// assert!((n.at(659.5) - 0.14).abs() < 1e-12 && (k.at(659.5) - 3.697).abs() < 1e-12);
/// ```
pub fn metal(name: &str) -> Option<(Value, Value)> {
    let t = table(name)?;
    let wavelengths: Vec<f64> = t.iter().map(|r| r.0).collect();
    let n = Value::Spectral {
        wavelengths: wavelengths.clone(),
        values: t.iter().map(|r| r.1).collect(),
    };
    let k = Value::Spectral {
        wavelengths,
        values: t.iter().map(|r| r.2).collect(),
    };
    Some((n, k))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fresnel::conductor;

    fn r0(n: f64, k: f64) -> f64 {
        ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k)
    }

    #[test]
    fn names_are_case_insensitive_and_unknown_is_none() {
        for name in ["Au", "au", "AU", "gold", "Ag", "cu", "AL", "aluminum"] {
            assert!(metal(name).is_some(), "{name}");
        }
        assert!(metal("Pt").is_none());
        assert!(metal("").is_none());
        for name in NAMES {
            assert!(metal(name).is_some());
        }
    }

    #[test]
    fn tables_are_valid_and_cover_the_visible_range() {
        for name in NAMES {
            let t = table(name).unwrap();
            assert!(
                t.first().unwrap().0 < 380.0 && t.last().unwrap().0 > 780.0,
                "{name}"
            );
            let (n, k) = metal(name).unwrap();
            n.validate("n", 0.0).unwrap();
            k.validate("k", 0.0).unwrap();
        }
    }

    #[test]
    fn values_match_the_cited_tables_at_tabulated_points() {
        // Spot checks typed from the papers' tables (J&C 1972 Table I; Rakić 1995).
        let checks = [
            ("Au", 659.5, 0.14, 3.697),
            ("Au", 450.9, 1.38, 1.914),
            ("Ag", 548.6, 0.06, 3.586),
            ("Cu", 616.8, 0.30, 3.205),
            ("Al", 563.57, 1.0728, 6.7839),
        ];
        for (name, nm, n_ref, k_ref) in checks {
            let (n, k) = metal(name).unwrap();
            assert!((n.at(nm) - n_ref).abs() < 1e-12, "{name} n at {nm}");
            assert!((k.at(nm) - k_ref).abs() < 1e-12, "{name} k at {nm}");
        }
    }

    #[test]
    fn gold_and_copper_are_reddish_silver_and_aluminium_are_bright() {
        let at = |name: &str, nm: f64| {
            let (n, k) = metal(name).unwrap();
            conductor(1.0, n.at(nm), k.at(nm))
        };
        // Gold: R(650) ≈ 0.95, R(450) ≈ 0.38 from J&C's n, k.
        assert!(at("Au", 650.0) > 0.9, "{}", at("Au", 650.0));
        assert!(at("Au", 450.0) < 0.45, "{}", at("Au", 450.0));
        assert!(at("Cu", 650.0) > 0.9 && at("Cu", 450.0) < 0.65);
        for nm in [450.0, 550.0, 650.0] {
            assert!(at("Ag", nm) > 0.9, "Ag {nm}");
            assert!(at("Al", nm) > 0.85, "Al {nm}");
        }
        // And the closed form at a tabulated point.
        let (n, k) = metal("Au").unwrap();
        assert!((conductor(1.0, n.at(659.5), k.at(659.5)) - r0(0.14, 3.697)).abs() < 1e-12);
    }
}
