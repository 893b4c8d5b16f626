//! The field checks a procedural spec's validation is written with: each names the field,
//! the value and what was expected.

use super::*;

pub(super) const POSITIVE: &str = "a finite number > 0";

pub(super) const UNIT: &str = "three finite numbers in [0, 1]";

pub(super) fn invalid(
    field: &'static str,
    value: String,
    expected: &'static str,
) -> ProceduralError {
    ProceduralError::Invalid {
        field,
        value,
        expected,
    }
}

pub(super) fn positive(field: &'static str, v: f32) -> Result<(), ProceduralError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(invalid(field, v.to_string(), POSITIVE))
    }
}

pub(super) fn positive_all(field: &'static str, v: &[f32]) -> Result<(), ProceduralError> {
    if v.iter().all(|x| x.is_finite() && *x > 0.0) {
        Ok(())
    } else {
        Err(invalid(field, format!("{v:?}"), "finite numbers > 0"))
    }
}

pub(super) fn color_ok(c: &[f32; 3]) -> bool {
    c.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x))
}

pub(super) fn unit_color(field: &'static str, c: &[f32; 3]) -> Result<(), ProceduralError> {
    if color_ok(c) {
        Ok(())
    } else {
        Err(invalid(field, format!("{c:?}"), UNIT))
    }
}
