//! The inspection as the `inspect` command prints it.

use super::*;

impl std::fmt::Display for Inspection {
    /// The report `splatter inspect` prints.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = |v: Vec3| format!("[{:.4}, {:.4}, {:.4}]", v.x, v.y, v.z);
        writeln!(
            f,
            "Gaussians:     {} (SH degree {})",
            self.count, self.sh_degree
        )?;
        writeln!(
            f,
            "bounds:        {} .. {}",
            v(self.bounds.0),
            v(self.bounds.1)
        )?;
        writeln!(
            f,
            "robust bounds: {} .. {} (1st-99th percentile per axis)",
            v(self.robust.0),
            v(self.robust.1)
        )?;
        writeln!(
            f,
            "floaters:      {} ({:.2}%) beyond the robust box grown by a quarter",
            self.floaters,
            100.0 * self.floaters as f64 / self.count.max(1) as f64
        )?;
        writeln!(
            f,
            "opacity:       median {:.3}, 1st-99th percentile {:.3} .. {:.3}",
            self.opacity.median, self.opacity.p1, self.opacity.p99
        )?;
        writeln!(
            f,
            "scale:         largest axis median {:.3e}, 1st-99th percentile {:.3e} .. {:.3e}",
            self.scale.median, self.scale.p1, self.scale.p99
        )?;
        let up = self.up_name();
        writeln!(f, "up:            {}", self.up_text())?;
        if let Some(c) = self
            .cameras
            .filter(|_| !matches!(self.evidence, UpEvidence::Cameras { .. }))
        {
            writeln!(
                f,
                "               not from the {} cameras: their ups disagree (agreement {:.2} < {CAMERAS_AGREEMENT})",
                c.count, c.agreement
            )?;
        }
        let scores: Vec<String> = AXES
            .iter()
            .zip(self.axis_scores)
            .map(|(a, s)| format!("{a} {s:+.3}"))
            .collect();
        writeln!(f, "               seen-top scores: {}", scores.join(", "))?;
        writeln!(
            f,
            "support:       at height {:.4} along up ({})",
            self.support,
            match self.evidence {
                UpEvidence::SupportPlane { .. } => "the support plane",
                _ => "the lowest dense layer: 1st percentile of the heights",
            }
        )?;
        if !self.labels.is_empty() {
            let listed: Vec<String> = self
                .labels
                .iter()
                .map(|(name, n)| format!("{name} ({n})"))
                .collect();
            writeln!(
                f,
                "labels:        {} (a scene selects them with {{\"label\": [..]}})",
                listed.join(", ")
            )?;
        }
        let t = self.placement(0.0);
        let (lo, hi) = self.upright_robust_bounds();
        let size = hi - lo;
        writeln!(
            f,
            "upright size:  {:.4} × {:.4} × {:.4} (robust, after the up rotation)",
            size.x, size.y, size.z
        )?;
        write!(
            f,
            "transform:     {{\"up\": {up}, \"translate\": [{:.4}, {:.4}, {:.4}]}} stands it on z = 0, centred on the z axis",
            t.x, t.y, t.z
        )
    }
}
