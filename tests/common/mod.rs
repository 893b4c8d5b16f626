//! Test data shared by the integration tests (`mod common;` in each). Each test binary
//! uses only part of it.
#![allow(dead_code)]

pub mod cli;

use splatter::sim::model::nacc::oracle::{Case3Variant, NaccParams};

/// The paper's fruit material (docs/method.md §9: kiwi/dragonfruit class).
pub fn fruit() -> NaccParams {
    NaccParams {
        e: 2000.0,
        nu: 0.38,
        alpha0: -0.04,
        beta: 1.0,
        xi: 2.0,
        m_slope: 2.36,
    }
}

/// A spread of the paper's materials (watermelon rind/flesh/seeds, jelly, sandcastle).
pub fn paper_materials() -> Vec<NaccParams> {
    let base = fruit();
    vec![
        base,
        NaccParams { beta: 2.0, ..base },
        NaccParams {
            e: 1000.0,
            beta: 0.6,
            ..base
        },
        NaccParams {
            e: 1e4,
            beta: 5.0,
            ..base
        },
        NaccParams {
            nu: 0.45,
            alpha0: -0.5,
            ..base
        },
        NaccParams {
            e: 50.0,
            nu: 0.05,
            beta: 0.01,
            xi: 1.0,
            ..base
        },
    ]
}

/// Every case-3 return mapping, `continuous` at three exponents.
pub const VARIANTS: [Case3Variant; 5] = [
    Case3Variant::Center,
    Case3Variant::Continuous { k: 1.0 },
    Case3Variant::Continuous { k: 2.0 },
    Case3Variant::Continuous { k: 8.0 },
    Case3Variant::ClosestPoint,
];
