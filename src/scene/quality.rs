//! `--quality`: one knob that scales a scene's resolution in space and on screen, so that a
//! scene written to run in minutes on a CPU (`standard`, as written) also renders at full
//! quality on a GPU (`high`) or as a quick preview (`draft`).
//!
//! A quality with length factor s (high ½, draft 2) multiplies every procedural object's
//! lattice spacing, the simulation's Δx, a given Δt (the CFL bound scales with Δx, and a
//! Δt computed from it follows by itself), a given fill spacing and a given particle
//! lattice spacing by s; it divides the
//! image size and the shadow volume's resolution by s. Particle counts go as s⁻³ and the
//! simulation's cost as s⁻⁴: `high` is about 16× the simulation work of `standard`.
//! Nothing else changes: the same objects, materials, paths and lights.

use super::physics::{FillSpec, ParticlesSpec};
use super::{Scene, MAX_IMAGE_SIZE};

/// How finely a scene is resolved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Quality {
    /// Twice as coarse: a fast preview (⅛ of the particles, half the image size).
    Draft,
    /// The scene as written.
    #[default]
    Standard,
    /// Twice as fine: 8× the particles, twice the image size (meant for a GPU).
    High,
}

impl Quality {
    /// The length factor s applied to spacings.
    pub fn length_factor(self) -> f64 {
        match self {
            Quality::Draft => 2.0,
            Quality::Standard => 1.0,
            Quality::High => 0.5,
        }
    }
}

impl Scene {
    /// Scale the scene's resolutions by `quality` (see the module docs). Image sizes stay
    /// within 1..=[`MAX_IMAGE_SIZE`]; the shadow resolution within 8..=256.
    pub fn apply_quality(&mut self, quality: Quality) {
        let s = quality.length_factor();
        if s == 1.0 {
            return;
        }
        for object in &mut self.objects {
            if let Some(p) = &mut object.procedural {
                p.spacing *= s as f32;
            }
            if let Some(FillSpec::Options(o)) =
                object.physics.as_mut().and_then(|p| p.fill.as_mut())
            {
                o.spacing = o.spacing.map(|h| h * s);
            }
            if let Some(ParticlesSpec::Lattice(o)) =
                object.physics.as_mut().map(|p| &mut p.particles)
            {
                o.spacing = o.spacing.map(|h| h * s);
            }
        }
        if let Some(sim) = &mut self.simulation {
            sim.dx *= s;
            sim.dt = sim.dt.map(|dt| dt * s);
        }
        let size = |v: u32| ((f64::from(v) / s).round() as u32).clamp(1, MAX_IMAGE_SIZE);
        let (w0, h0) = (self.output.width, self.output.height);
        let (w, h) = (size(w0), size(h0));
        // Focal lengths in pixels follow the image, so that the field of view stays.
        if let (Some(fx), Some(fy)) = (self.camera.fx, self.camera.fy) {
            self.camera.fx = Some(fx * w as f32 / w0.max(1) as f32);
            self.camera.fy = Some(fy * h as f32 / h0.max(1) as f32);
        }
        self.output.width = w;
        self.output.height = h;
        if let Some(l) = &mut self.lighting {
            l.shadows.resolution =
                ((f64::from(l.shadows.resolution) / s).round() as u32).clamp(8, 256);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn high_halves_spacings_and_doubles_the_image() {
        let mut scene = crate::scene::parse(
            r#"{ "output": { "width": 320, "height": 180, "frames": 2 },
                 "camera": { "fx": 300, "fy": 300, "path": { "type": "orbit", "radius": 2 } },
                 "simulation": { "dx": 0.02, "dt": 1e-4,
                                 "domain": { "lo": [-1, -1, -1], "hi": [1, 1, 1] } },
                 "objects": [ { "procedural": { "shape": "sphere", "radius": 0.2,
                                                "spacing": 0.02, "color": [1, 0, 0] },
                                "physics": { "material": { "model": "fixed_corotated",
                                                           "E": 1000, "nu": 0.3, "density": 1 },
                                             "fill": { "spacing": 0.01 } } } ] }"#,
            "test.json",
            std::path::Path::new("."),
        )
        .expect("a valid scene");
        scene.apply_quality(Quality::High);
        let sim = scene.simulation.as_ref().expect("simulation");
        assert_eq!((sim.dx, sim.dt), (0.01, Some(5e-5)));
        assert_eq!(
            scene.objects[0].procedural.as_ref().map(|p| p.spacing),
            Some(0.01)
        );
        let fill = scene.objects[0]
            .physics
            .as_ref()
            .and_then(|p| p.fill.clone());
        assert!(matches!(fill, Some(FillSpec::Options(o)) if o.spacing == Some(0.005)));
        assert_eq!((scene.output.width, scene.output.height), (640, 360));
        assert_eq!(
            (scene.camera.fx, scene.camera.fy),
            (Some(600.0), Some(600.0))
        );
        scene.apply_quality(Quality::Draft);
        assert_eq!(
            scene.objects[0].procedural.as_ref().map(|p| p.spacing),
            Some(0.02)
        );
        assert_eq!((scene.output.width, scene.output.height), (320, 180));
    }
}
