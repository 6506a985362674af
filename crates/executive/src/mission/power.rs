//! The mission's `[power]` table: the simulated solar panel, battery and loads
//! ([`rovernav_sim::PowerConfig`]) and the executive's sleep and wake thresholds
//! ([`crate::power::PowerPolicy`]). Every field is optional; unset ones keep the defaults of a
//! small rover.

use crate::power::PowerPolicy;
use rovernav_sim::PowerConfig;
use serde::Deserialize;

/// The `[power]` table.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PowerSpec {
    /// Battery capacity (Wh).
    pub capacity_wh: Option<f64>,
    /// Charge at the start, as a fraction of the capacity (0..1).
    pub initial_charge: Option<f64>,
    /// Solar panel area (m^2).
    pub panel_area_m2: Option<f64>,
    /// Solar cell efficiency (0..1).
    pub panel_efficiency: Option<f64>,
    /// Solar flux at the ground on a surface facing the sun (W/m^2).
    pub irradiance_w_m2: Option<f64>,
    /// Local true solar time at the start (hours, 0..24).
    pub local_time_h: Option<f64>,
    /// Site latitude (deg).
    pub latitude_deg: Option<f64>,
    /// Season: areocentric solar longitude (deg).
    pub ls_deg: Option<f64>,
    /// Computer load awake (W).
    pub computer_w: Option<f64>,
    /// Computer load asleep (W).
    pub sleep_w: Option<f64>,
    /// Rover mass for the motors' load (kg).
    pub mass_kg: Option<f64>,
    /// Energy per camera image (J).
    pub camera_j_per_image: Option<f64>,
    /// Sleep below this state of charge (0..1).
    pub sleep_below: Option<f64>,
    /// Wake at this state of charge (0..1).
    pub wake_above: Option<f64>,
    /// Time between readings while asleep (s).
    pub check_s: Option<f64>,
}

impl PowerSpec {
    /// The simulator's power system.
    pub fn config(&self) -> PowerConfig {
        let d = PowerConfig::default();
        PowerConfig {
            capacity_wh: self.capacity_wh.unwrap_or(d.capacity_wh),
            initial_charge: self.initial_charge.unwrap_or(d.initial_charge),
            panel_area_m2: self.panel_area_m2.unwrap_or(d.panel_area_m2),
            panel_efficiency: self.panel_efficiency.unwrap_or(d.panel_efficiency),
            irradiance_w_m2: self.irradiance_w_m2.unwrap_or(d.irradiance_w_m2),
            local_time_h: self.local_time_h.unwrap_or(d.local_time_h),
            latitude_deg: self.latitude_deg.unwrap_or(d.latitude_deg),
            ls_deg: self.ls_deg.unwrap_or(d.ls_deg),
            computer_w: self.computer_w.unwrap_or(d.computer_w),
            sleep_w: self.sleep_w.unwrap_or(d.sleep_w),
            mass_kg: self.mass_kg.unwrap_or(d.mass_kg),
            camera_j_per_image: self.camera_j_per_image.unwrap_or(d.camera_j_per_image),
            ..d
        }
    }

    /// The executive's thresholds.
    pub fn policy(&self) -> PowerPolicy {
        let d = PowerPolicy::default();
        PowerPolicy {
            sleep_below: self.sleep_below.unwrap_or(d.sleep_below),
            wake_above: self.wake_above.unwrap_or(d.wake_above),
            check_s: self.check_s.unwrap_or(d.check_s),
        }
    }

    /// Checks every field; the error names it (without the `power.` prefix).
    pub(super) fn check(&self) -> Result<(), (&'static str, String)> {
        use super::check::{in_range, positive_up_to};
        let c = self.config();
        let p = self.policy();
        let checks: [(&'static str, Result<(), String>); 15] = [
            ("capacity_wh", positive_up_to(c.capacity_wh, 1.0e6, " Wh")),
            ("initial_charge", in_range(c.initial_charge, 0.0, 1.0, "")),
            ("panel_area_m2", in_range(c.panel_area_m2, 0.0, 100.0, " m^2")),
            ("panel_efficiency", in_range(c.panel_efficiency, 0.0, 1.0, "")),
            ("irradiance_w_m2", in_range(c.irradiance_w_m2, 0.0, 2000.0, " W/m^2")),
            ("local_time_h", in_range(c.local_time_h, 0.0, 24.0, " h")),
            ("latitude_deg", in_range(c.latitude_deg, -90.0, 90.0, " deg")),
            ("ls_deg", in_range(c.ls_deg, 0.0, 360.0, " deg")),
            ("computer_w", in_range(c.computer_w, 0.0, 1.0e4, " W")),
            ("sleep_w", in_range(c.sleep_w, 0.0, 1.0e4, " W")),
            ("mass_kg", positive_up_to(c.mass_kg, 1.0e4, " kg")),
            ("camera_j_per_image", in_range(c.camera_j_per_image, 0.0, 1.0e5, " J")),
            ("sleep_below", in_range(p.sleep_below, 0.0, 1.0, "")),
            ("wake_above", in_range(p.wake_above, 0.0, 1.0, "")),
            ("check_s", in_range(p.check_s, 1.0, 3600.0, " s")),
        ];
        for (field, result) in checks {
            result.map_err(|why| (field, why))?;
        }
        if p.wake_above <= p.sleep_below {
            return Err(("wake_above", format!("must be above sleep_below ({})", p.sleep_below)));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::Mission;

    fn with_power(table: &str) -> Result<Mission, String> {
        let text = format!("{}\n[power]\n{table}\n", crate::mission::DEFAULT_MISSION_TOML);
        Mission::from_toml(&text, "m.toml").map_err(|e| e.to_string())
    }

    #[test]
    fn the_power_table_sets_the_simulator_and_the_thresholds_and_bad_fields_are_named() {
        let m = with_power("capacity_wh = 80.0\ninitial_charge = 0.1\nwake_above = 0.9").unwrap();
        assert_eq!(m.power.config().capacity_wh, 80.0);
        assert_eq!(m.power.config().initial_charge, 0.1);
        assert_eq!(m.power.config().computer_w, 12.0, "unset fields keep the defaults");
        assert_eq!(m.power.policy().wake_above, 0.9);
        for (table, field) in [
            ("initial_charge = 1.5", "power.initial_charge"),
            ("capacity_wh = 0.0", "power.capacity_wh"),
            ("check_s = nan", "power.check_s"),
            ("sleep_below = 0.7", "power.wake_above"),
        ] {
            let e = with_power(table).unwrap_err();
            assert!(e.contains(&format!("field `{field}`")), "{table}: {e}");
        }
        let e = with_power("battery = 3").unwrap_err();
        assert!(e.contains("unknown field `battery`"), "{e}");
    }
}
