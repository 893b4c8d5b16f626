//! The source paper's Table A1 read for stability: the CFL number Δt_step · c / Δx of every
//! material of every example, with c = sqrt((λ + 2μ)/ρ), under the literal reading of its
//! density column (ρ = 2) and under the reading this project uses (ρ = 200, the density
//! convention of the PhysGaussian code the paper's examples are set up in). The reasoning is
//! in docs/method.md §9.2; `splatter-lab accuracy` writes the table to `OUT/data/table_a1.md`.

use serde::{Deserialize, Serialize};

use crate::suite::PAPER_EXAMPLES;
use splatter::sim::model::elasticity::Lame;

/// The density column as printed: "2" in every row.
pub const DENSITY_LITERAL: f64 = 2.0;

/// The density the scenes use: the column read as 2 × 10², in kg/m³ with E in Pa.
pub const DENSITY_READ: f64 = 200.0;

/// The explicit step is stable below CFL ≈ 1 in theory; the stability atlas
/// (docs/notes/stability.md) saw every return mapping fail from 1.5 on.
pub const CFL_UNSTABLE: f64 = 1.0;

/// One material of an example: (example, component, E, ν), as in docs/method.md §9.1.
pub const MATERIALS: [(&str, &str, f64, f64); 10] = [
    ("watermelon", "rind", 2000.0, 0.38),
    ("watermelon", "flesh", 1000.0, 0.38),
    ("watermelon", "seeds", 1e4, 0.38),
    ("jelly", "", 2000.0, 0.45),
    ("pumpkin", "", 4000.0, 0.40),
    ("kiwi", "", 2000.0, 0.42),
    ("pineapple", "", 5000.0, 0.39),
    ("dragonfruit", "", 2000.0, 0.42),
    ("toast", "", 2000.0, 0.38),
    ("sandcastle", "", 50.0, 0.05),
];

/// One row of the table: a material's wave speed and CFL number under both readings.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CflRow {
    pub example: String,
    pub component: String,
    pub e: f64,
    pub nu: f64,
    pub dx: f64,
    pub dt_step: f64,
    /// Wave speed c (m/s) and CFL number Δt c / Δx with ρ = 2.
    pub c_literal: f64,
    pub cfl_literal: f64,
    /// The same with ρ = 200.
    pub c_read: f64,
    pub cfl_read: f64,
}

/// Elastic wave speed c = sqrt((λ + 2μ)/ρ).
pub fn wave_speed(e: f64, nu: f64, density: f64) -> f64 {
    (Lame::from_young_poisson(e, nu).p_wave_modulus() / density).sqrt()
}

/// Every material of Table A1 with its example's Δx and Δt_step.
pub fn cfl_rows() -> Vec<CflRow> {
    MATERIALS
        .iter()
        .map(|&(example, component, e, nu)| {
            let row = PAPER_EXAMPLES
                .iter()
                .find(|x| x.name == example)
                .expect("every material names an example of PAPER_EXAMPLES");
            let cfl = |c: f64| row.dt_step * c / row.dx;
            let c_literal = wave_speed(e, nu, DENSITY_LITERAL);
            let c_read = wave_speed(e, nu, DENSITY_READ);
            CflRow {
                example: example.into(),
                component: component.into(),
                e,
                nu,
                dx: row.dx,
                dt_step: row.dt_step,
                c_literal,
                cfl_literal: cfl(c_literal),
                c_read,
                cfl_read: cfl(c_read),
            }
        })
        .collect()
}

/// The markdown table of docs/method.md §9.2.
pub fn markdown(rows: &[CflRow]) -> String {
    let mut s = String::from(
        "| example | E (Pa) | ν | Δx | Δt_step | c, ρ 2 (m/s) | CFL, ρ 2 | c, ρ 200 (m/s) | CFL, ρ 200 |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let name = if r.component.is_empty() {
            r.example.clone()
        } else {
            format!("{} ({})", r.example, r.component)
        };
        let flag = |cfl: f64| {
            if cfl > CFL_UNSTABLE {
                format!("**{cfl:.2}**")
            } else {
                format!("{cfl:.2}")
            }
        };
        s += &format!(
            "| {name} | {} | {} | {:e} | {:e} | {:.1} | {} | {:.2} | {} |\n",
            r.e,
            r.nu,
            r.dx,
            r.dt_step,
            r.c_literal,
            flag(r.cfl_literal),
            r.c_read,
            flag(r.cfl_read)
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_literal_density_puts_the_watermelon_and_the_pumpkin_past_the_cfl_limit() {
        let rows = cfl_rows();
        let unstable: Vec<String> = rows
            .iter()
            .filter(|r| r.cfl_literal > CFL_UNSTABLE)
            .map(|r| format!("{} {}", r.example, r.component))
            .collect();
        assert_eq!(
            unstable,
            [
                "watermelon rind",
                "watermelon flesh",
                "watermelon seeds",
                "pumpkin "
            ],
            "{rows:#?}"
        );
        let seeds = &rows[2];
        // c = sqrt((λ + 2μ)/ρ) by hand: E 1e4, ν 0.38 gives λ + 2μ = 18 725 Pa.
        assert!((seeds.c_literal - (18_725.0f64 / 2.0).sqrt()).abs() < 0.5);
        assert!((seeds.cfl_literal - 3.23).abs() < 0.01);
    }

    #[test]
    fn density_200_makes_every_row_stable_with_margin() {
        for r in cfl_rows() {
            assert!(r.cfl_read < 0.35, "{r:?}");
            // c scales as 1/sqrt(ρ): a hundredfold density, a tenth of the speed.
            assert!((r.c_literal / r.c_read - 10.0).abs() < 1e-9);
        }
    }
}
