//! A [`Report`] as the text `brdftab check` prints.

use std::fmt;

use super::Report;

fn yes_no(b: bool) -> &'static str {
    if b { "yes" } else { "NO" }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "source:             {}", self.source)?;
        writeln!(f, "channels:           {}", self.channels.join(" "))?;
        writeln!(
            f,
            "positive:           {}   (min value {:.4e} over {} pairs, {} non-finite)",
            yes_no(self.positive),
            self.min_value,
            self.pairs,
            self.non_finite
        )?;
        write!(
            f,
            "reciprocal:         {}   (max relative error {:.3e}, tolerance {:.0e}; declared {})",
            yes_no(self.reciprocal),
            self.max_reciprocity_error,
            self.reciprocity_tolerance,
            if self.declared.reciprocal {
                "yes"
            } else {
                "no"
            }
        )?;
        if let (false, Some([a, b])) = (self.reciprocal, self.max_reciprocity_at) {
            write!(
                f,
                "\n                    worst at wi (θ {:.1}°, φ {:.1}°), wo (θ {:.1}°, φ {:.1}°)",
                a.theta, a.phi, b.theta, b.phi
            )?;
        }
        writeln!(f)?;
        writeln!(
            f,
            "energy conserving:  {}   (max albedo {:.6} at θ′ = {}°{}, channel {})",
            yes_no(self.energy_conserving),
            self.max_albedo,
            self.max_albedo_theta_deg,
            if self.max_albedo_phi_deg != 0.0 {
                format!(", φ′ = {}°", self.max_albedo_phi_deg)
            } else {
                String::new()
            },
            self.max_albedo_channel
        )?;
        writeln!(
            f,
            "declared flags:     reciprocal {}, isotropic {}, bilateral {}, delta {}, transmission {}",
            self.declared.reciprocal,
            self.declared.isotropic,
            self.declared.bilateral,
            self.declared.delta,
            self.declared.transmission
        )?;
        writeln!(
            f,
            "albedo curve (θ′ in degrees every 5° and the last; one column per channel):"
        )?;
        let last = self.albedo_curve.len().saturating_sub(1);
        for (i, p) in self.albedo_curve.iter().enumerate() {
            if p.theta_deg % 5.0 != 0.0 && i != last {
                continue;
            }
            let vals: Vec<String> = p.albedo.iter().map(|a| format!("{a:.6}")).collect();
            writeln!(f, "  {:>5} {}", p.theta_deg, vals.join(" "))?;
        }
        Ok(())
    }
}
