//! Range checks shared by settings and weather validation; every error names its field path.

use glam::Vec3;

use crate::error::{Error, Result};

pub(crate) fn invalid(field: impl Into<String>, reason: impl Into<String>) -> Error {
    Error::InvalidSettings {
        field: field.into(),
        reason: reason.into(),
    }
}

pub(crate) fn finite(field: &str, v: f32) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(invalid(field, format!("must be finite, got {v}")))
    }
}

pub(crate) fn in_range(field: &str, v: f32, lo: f32, hi: f32) -> Result<()> {
    finite(field, v)?;
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(invalid(field, format!("must be in [{lo}, {hi}], got {v}")))
    }
}

pub(crate) fn positive(field: &str, v: f32) -> Result<()> {
    finite(field, v)?;
    if v > 0.0 {
        Ok(())
    } else {
        Err(invalid(field, format!("must be > 0, got {v}")))
    }
}

pub(crate) fn non_negative(field: &str, v: f32) -> Result<()> {
    finite(field, v)?;
    if v >= 0.0 {
        Ok(())
    } else {
        Err(invalid(field, format!("must be >= 0, got {v}")))
    }
}

pub(crate) fn color(field: &str, c: Vec3) -> Result<()> {
    if c.is_finite() && c.min_element() >= 0.0 {
        Ok(())
    } else {
        Err(invalid(
            field,
            format!("must be finite and non-negative, got {c}"),
        ))
    }
}

pub(crate) fn pow2(field: &str, v: u32, lo: u32, hi: u32) -> Result<()> {
    if v.is_power_of_two() && (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(invalid(
            field,
            format!("must be a power of two in [{lo}, {hi}], got {v}"),
        ))
    }
}

pub(crate) fn count(field: &str, v: u32, lo: u32, hi: u32) -> Result<()> {
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(invalid(field, format!("must be in [{lo}, {hi}], got {v}")))
    }
}
