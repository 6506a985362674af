//! The sun's direction from local solar time, latitude and season.
//!
//! Standard spherical astronomy (e.g. Meeus, "Astronomical Algorithms", ch. 13), with Mars'
//! obliquity for the declination (Allison and McEwen 2000): the solar declination is
//! `delta = asin(sin(25.19 deg) sin(Ls))` at areocentric solar longitude `Ls`; the hour angle is
//! `H = 15 deg/h * (t - 12 h)` in local true solar time (a Mars hour being 1/24 sol); then
//!
//! - elevation: `sin(e) = sin(phi) sin(delta) + cos(phi) cos(delta) cos(H)`,
//! - azimuth east of north: `A = atan2(-cos(delta) sin(H), cos(phi) sin(delta) - sin(phi) cos(delta) cos(H))`.
//!
//! The world frame is x east, y north, z up, so the unit vector towards the sun is
//! `(sin A cos e, cos A cos e, sin e)`.

/// Mars' obliquity (rad).
pub const MARS_OBLIQUITY_DEG: f64 = 25.19;

/// The sun as seen from the site.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    /// Azimuth east of north (rad).
    pub azimuth: f64,
    /// Elevation above the horizon (rad, negative at night).
    pub elevation: f64,
}

impl Sun {
    /// The sun at local true solar time `hours` (0..24), latitude `latitude_deg` and solar
    /// declination `declination_deg`.
    pub fn at(hours: f64, latitude_deg: f64, declination_deg: f64) -> Self {
        let h = (15.0 * (hours - 12.0)).to_radians();
        let (phi, delta) = (latitude_deg.to_radians(), declination_deg.to_radians());
        let sin_e = phi.sin() * delta.sin() + phi.cos() * delta.cos() * h.cos();
        let elevation = sin_e.clamp(-1.0, 1.0).asin();
        let azimuth =
            (-delta.cos() * h.sin()).atan2(phi.cos() * delta.sin() - phi.sin() * delta.cos() * h.cos());
        Self { azimuth, elevation }
    }

    /// The sun on Mars at local true solar time `hours`, latitude `latitude_deg` and areocentric
    /// solar longitude `ls_deg` (the season: 0 northern spring equinox, 90 northern summer).
    pub fn on_mars(hours: f64, latitude_deg: f64, ls_deg: f64) -> Self {
        let declination = (MARS_OBLIQUITY_DEG.to_radians().sin() * ls_deg.to_radians().sin()).asin();
        Self::at(hours, latitude_deg, declination.to_degrees())
    }

    /// Unit vector towards the sun in the world frame (x east, y north, z up).
    pub fn direction(&self) -> [f64; 3] {
        let (se, ce) = self.elevation.sin_cos();
        let (sa, ca) = self.azimuth.sin_cos();
        [sa * ce, ca * ce, se]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noon_at_the_equator_on_the_equinox_is_overhead() {
        let s = Sun::at(12.0, 0.0, 0.0);
        assert!((s.elevation - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
    }

    #[test]
    fn morning_sun_is_east_afternoon_west_and_elevation_matches_the_equinox_formula() {
        // On the equinox the sun rises due east and e = asin(cos(phi) cos(H)).
        for (t, lat) in [(9.0, -14.6), (15.5, 20.0), (7.0, 0.0)] {
            let s = Sun::at(t, lat, 0.0);
            let h = (15.0f64 * (t - 12.0)).to_radians();
            let expected = (lat.to_radians().cos() * h.cos()).asin();
            assert!((s.elevation - expected).abs() < 1e-9);
            let d = s.direction();
            assert!(if t < 12.0 { d[0] > 0.0 } else { d[0] < 0.0 }, "{t}: {d:?}");
            let n: f64 = d.iter().map(|v| v * v).sum();
            assert!((n - 1.0).abs() < 1e-12);
        }
        // Noon in the southern hemisphere on the equinox: the sun is due north at 90 - |lat|.
        let s = Sun::at(12.0, -30.0, 0.0);
        assert!(s.azimuth.abs() < 1e-9 && (s.elevation.to_degrees() - 60.0).abs() < 1e-9);
        // Northern summer solstice on Mars: declination = obliquity.
        let s = Sun::on_mars(12.0, MARS_OBLIQUITY_DEG, 90.0);
        assert!((s.elevation.to_degrees() - 90.0).abs() < 1e-6);
    }
}
