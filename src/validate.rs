//! Range checks shared by settings and weather validation; every error names its field path.

use glam::Vec3;

use crate::error::{Error, Result};

pub(crate) fn invalid(field: impl Into<String>, reason: impl Into<String>) -> Error {
    Error::InvalidSettings {
        field: field.into(),
        reason: reason.into(),
    }
}

/// A number for a message: plain when it reads well, else in scientific notation with six
/// significant digits (a C host's 1e300 would otherwise print as 301 digits).
pub(crate) fn num(v: impl Into<f64>) -> String {
    let v: f64 = v.into();
    let a = v.abs();
    if !v.is_finite() || v == 0.0 || (1e-4..1e7).contains(&a) {
        // Shortest round-trip form, at most a few digits for these magnitudes.
        let s = format!("{v}");
        if s.len() <= 16 {
            return s;
        }
        return format!("{v:.6}").trim_end_matches('0').to_string();
    }
    format!("{v:.5e}")
}

/// A vector for a message, each component as `num` writes it.
pub(crate) fn vec(v: Vec3) -> String {
    format!("[{}, {}, {}]", num(v.x), num(v.y), num(v.z))
}

pub(crate) fn finite(field: &str, v: f32) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(invalid(field, format!("must be finite, got {}", num(v))))
    }
}

pub(crate) fn in_range(field: &str, v: f32, lo: f32, hi: f32) -> Result<()> {
    finite(field, v)?;
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(invalid(
            field,
            format!("must be in [{}, {}], got {}", num(lo), num(hi), num(v)),
        ))
    }
}

pub(crate) fn positive(field: &str, v: f32) -> Result<()> {
    finite(field, v)?;
    if v > 0.0 {
        Ok(())
    } else {
        Err(invalid(field, format!("must be > 0, got {}", num(v))))
    }
}

pub(crate) fn non_negative(field: &str, v: f32) -> Result<()> {
    finite(field, v)?;
    if v >= 0.0 {
        Ok(())
    } else {
        Err(invalid(field, format!("must be >= 0, got {}", num(v))))
    }
}

pub(crate) fn color(field: &str, c: Vec3) -> Result<()> {
    if c.is_finite() && c.min_element() >= 0.0 {
        Ok(())
    } else {
        Err(invalid(
            field,
            format!("must be finite and non-negative, got {}", vec(c)),
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

#[cfg(test)]
mod tests {
    use super::num;

    #[test]
    fn numbers_in_messages_stay_short() {
        assert_eq!(num(-1e300), "-1.00000e300");
        assert_eq!(num(200_000.0f32), "200000");
        assert_eq!(num(0.5f32), "0.5");
        assert_eq!(num(f32::NAN), "NaN");
        assert_eq!(num(f64::NEG_INFINITY), "-inf");
        assert!(num(1.0f32 / 3.0).len() <= 10, "{}", num(1.0f32 / 3.0));
        assert!(num(3.4e38f32).len() < 14);
    }
}
