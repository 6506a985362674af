//! One validation layer for the numbers and names of missions and campaigns (issue 44): each
//! check gives `Err(why)` in one line, and the caller names the file, line and field. Campaign
//! files (`rovernav_campaign::spec`) use the same checks for the fields they share with missions.

use super::RoverSpec;

/// Largest magnitude of a coordinate (m): beyond any local frame and any projected easting or
/// northing on Mars, so a typo such as `1e308` is refused before a grid is sized from it.
pub const MAX_COORDINATE_M: f64 = 1.0e7;

/// Largest arrival tolerance (m): a tolerance wider than this would report `reached` far from
/// the goal.
pub const MAX_TOLERANCE_M: f64 = 10.0;

/// Largest crater density (craters of diameter at least 1 m per hectare: one per square metre).
pub const MAX_CRATERS_PER_HECTARE: f64 = 10_000.0;

/// Largest expected crater count of one yard (density times area), bounding generation time.
pub const MAX_CRATERS_PER_YARD: f64 = 1.0e5;

/// `v` is a finite number in `[min, max]` (`unit` for the message, e.g. `m`).
pub fn in_range(v: f64, min: f64, max: f64, unit: &str) -> Result<(), String> {
    if v.is_finite() && (min..=max).contains(&v) {
        Ok(())
    } else {
        Err(format!("must be a finite number in [{min}, {max}]{unit}, got {}", shown(v)))
    }
}

/// `v` is a finite number in `(0, max]`.
pub fn positive_up_to(v: f64, max: f64, unit: &str) -> Result<(), String> {
    if v.is_finite() && v > 0.0 && v <= max {
        Ok(())
    } else {
        Err(format!("must be a finite number in (0, {max}]{unit}, got {}", shown(v)))
    }
}

/// The 1-based line holding the key of a dotted `field` (`goal.waypoints[0]` looks for
/// `waypoints =`) when exactly one line of `text` does.
pub fn line_of(text: &str, field: &str) -> Option<usize> {
    let key = field.rsplit('.').next().unwrap_or(field).split('[').next().unwrap_or_default();
    let lines: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| {
            l.trim_start().strip_prefix(key).is_some_and(|rest| rest.trim_start().starts_with('='))
        })
        .map(|(i, _)| i + 1)
        .collect();
    match lines.as_slice() {
        [line] if !key.is_empty() => Some(*line),
        _ => None,
    }
}

/// A number as a message shows it: in scientific notation when huge (`1e308`, not 309 digits).
fn shown(v: f64) -> String {
    if v.is_finite() && v.abs() >= 1.0e9 { format!("{v:e}") } else { v.to_string() }
}

/// A coordinate (local or projected metres).
pub fn coordinate(v: f64) -> Result<(), String> {
    in_range(v, -MAX_COORDINATE_M, MAX_COORDINATE_M, " m")
}

/// An arrival tolerance (m).
pub fn tolerance(v: f64) -> Result<(), String> {
    positive_up_to(v, MAX_TOLERANCE_M, " m")
}

/// A crater density on a square yard of side `size_m`.
pub fn craters_per_hectare(v: f64, size_m: f64) -> Result<(), String> {
    in_range(v, 0.0, MAX_CRATERS_PER_HECTARE, " per hectare")?;
    let expected = v * size_m * size_m / 10_000.0;
    if expected > MAX_CRATERS_PER_YARD {
        return Err(format!(
            "{v} per hectare on a {size_m} m yard is {expected:.0} craters, over {MAX_CRATERS_PER_YARD}"
        ));
    }
    Ok(())
}

/// A name used as an output folder: one plain path component (no `/`, `\`, `..`, absolute path,
/// drive letter or control character), at most 100 characters.
pub fn output_name(name: &str) -> Result<(), String> {
    let plain = !name.is_empty()
        && name.chars().count() <= 100
        && name != "."
        && name != ".."
        && !name.chars().any(|c| c.is_control() || "/\\:".contains(c));
    if plain {
        Ok(())
    } else {
        Err(format!(
            "{name:?} must be a plain name of at most 100 characters (no '/', '\\', ':', \"..\" or control characters): outputs go in a folder of that name"
        ))
    }
}

impl RoverSpec {
    /// The first override out of range, as (field under `rover.`, why).
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        let fields = [
            ("length_m", self.length_m, 0.05, 20.0, " m"),
            ("width_m", self.width_m, 0.05, 20.0, " m"),
            ("clearance_m", self.clearance_m, 0.005, 5.0, " m"),
            ("max_tilt_deg", self.max_tilt_deg, 1.0, 89.0, " deg"),
            ("max_speed_mps", self.max_speed_mps, 0.001, 10.0, " m/s"),
            ("mast_range_m", self.mast_range_m, 0.1, 1000.0, " m"),
            ("mast_fov_deg", self.mast_fov_deg, 1.0, 179.0, " deg"),
        ];
        for (field, value, min, max, unit) in fields {
            if let Some(v) = value {
                in_range(v, min, max, unit).map_err(|why| (field, why))?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_that_leave_the_output_folder_are_refused() {
        for bad in ["/tmp/x", "../x", "a/../../b", "..", "a\\b", "C:x", "", "a\nb"] {
            assert!(output_name(bad).is_err(), "{bad:?}");
        }
        for good in ["default-mars-yard", "gale traverse", "a..b", "v1.2"] {
            assert!(output_name(good).is_ok(), "{good:?}");
        }
    }

    #[test]
    fn ranges_refuse_nan_and_infinities() {
        for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e308] {
            assert!(coordinate(v).is_err() && tolerance(v).is_err(), "{v}");
        }
        assert!(tolerance(0.0).is_err() && tolerance(0.5).is_ok());
        assert!(craters_per_hectare(1e9, 30.0).is_err() && craters_per_hectare(40.0, 30.0).is_ok());
        assert!(craters_per_hectare(10_000.0, 2000.0).is_err());
    }
}
