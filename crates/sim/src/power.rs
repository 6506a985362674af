//! The rover's power system: a solar panel, a battery and the loads of the computer, the drive
//! motors and the cameras, reported as SR2's power telemetry (paper 001 section 3: "current
//! sensors and voltage dividers were used to monitor system current and solar panel voltages";
//! "the system could switch to SLEEP mode if the battery voltage was too low and wake up when
//! the battery is charged").
//!
//! - Panel: a horizontal panel under the sun of [`crate::render::Sun::on_mars`],
//!   `P = A eta F max(0, sin e)`, the elevation `e` from local true solar time, which advances
//!   with simulated time (one Mars hour is 1/24 of a 88 775.244 s sol). With
//!   `sin e = a + b cos H` (`a = sin phi sin delta`, `b = cos phi cos delta`, `H` the hour angle)
//!   the energy over an interval is integrated in closed form, sunrise and sunset included.
//! - Battery: an energy store between 0 and its capacity; the panel's surplus over a full
//!   battery is shunted away, a demand it cannot meet counts as unmet (a brown-out).
//! - Loads: the computer (its sleep-mode draw while asleep); the motors
//!   `P = m g (c_rr |v| + c_turn |v_l - v_r| / 2 + max(0, sin grade) |v|) / eta_drive` from the
//!   wheel speeds; the cameras a fixed energy per image (a stereo range image or a LIDAR nod
//!   counts two).
//!
//! Departures, each for a reason: the flux at the surface is a constant `F` (no Beer's-law
//! extinction growing towards the horizon), so the output follows `sin e` exactly and the
//! operator can check it; the panel stays horizontal as the rover pitches and rolls (a few
//! degrees on the yards); the state of charge is read directly (a fuel gauge) instead of SR2's
//! battery voltage, whose curve against charge the paper does not give; no charge or discharge
//! losses and no temperature.

use crate::render::sun::MARS_OBLIQUITY_DEG;
use rovernav_core::PowerReading;
use std::f64::consts::{PI, TAU};

/// One Mars solar day (s).
pub const SOL_S: f64 = 88_775.244;
/// Mars surface gravity (m/s^2).
const MARS_GRAVITY: f64 = 3.711;

/// The power system's parameters (the mission's `[power]` table); defaults for a small
/// solar rover of SR2's class.
#[derive(Clone, Debug, PartialEq)]
pub struct PowerConfig {
    /// Battery capacity (Wh).
    pub capacity_wh: f64,
    /// Charge at the start, as a fraction of the capacity.
    pub initial_charge: f64,
    /// Solar panel area (m^2).
    pub panel_area_m2: f64,
    /// Solar cell efficiency (0..1).
    pub panel_efficiency: f64,
    /// Solar flux on a surface facing the sun, at the ground (W/m^2).
    pub irradiance_w_m2: f64,
    /// Local true solar time at the start of the run (hours).
    pub local_time_h: f64,
    /// Site latitude (deg).
    pub latitude_deg: f64,
    /// Areocentric solar longitude, the season (deg).
    pub ls_deg: f64,
    /// Computer load while awake (W).
    pub computer_w: f64,
    /// Computer load in sleep mode (W).
    pub sleep_w: f64,
    /// Rover mass (kg).
    pub mass_kg: f64,
    /// Rolling resistance coefficient of driving.
    pub rolling_resistance: f64,
    /// Resistance coefficient of skid-steered turning (per unit of differential wheel speed).
    pub turn_resistance: f64,
    /// Efficiency of the motors and gears (0..1).
    pub drive_efficiency: f64,
    /// Energy per camera image (J).
    pub camera_j_per_image: f64,
}

impl Default for PowerConfig {
    /// A small rover: 150 Wh of battery, a 0.4 m^2 panel of 20 % cells under 500 W/m^2 (40 W
    /// with the sun overhead), a 12 W computer sleeping at 1 W, 20 kg, 5 J an image, at the
    /// images' site and time (Gale crater, 13:00, northern spring).
    fn default() -> Self {
        Self {
            capacity_wh: 150.0,
            initial_charge: 1.0,
            panel_area_m2: 0.4,
            panel_efficiency: 0.2,
            irradiance_w_m2: 500.0,
            local_time_h: 13.0,
            latitude_deg: -4.6,
            ls_deg: 0.0,
            computer_w: 12.0,
            sleep_w: 1.0,
            mass_kg: 20.0,
            rolling_resistance: 0.15,
            turn_resistance: 0.5,
            drive_efficiency: 0.3,
            camera_j_per_image: 5.0,
        }
    }
}

/// Energy totals since the start (Wh).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyTotals {
    /// Produced by the panel.
    pub panel_wh: f64,
    /// Used by the computer.
    pub computer_wh: f64,
    /// Used by the drive motors.
    pub motors_wh: f64,
    /// Used by the cameras.
    pub cameras_wh: f64,
    /// Panel surplus shunted away with the battery full.
    pub shunted_wh: f64,
    /// Demand the empty battery could not meet.
    pub unmet_wh: f64,
}

/// The power system during a run.
#[derive(Clone, Debug)]
pub struct PowerModel {
    config: PowerConfig,
    charge_wh: f64,
    clock: f64,
    asleep: bool,
    totals: EnergyTotals,
    /// Totals and clock at the start of the current command.
    mark: (EnergyTotals, f64),
}

impl PowerModel {
    /// The power system at time 0.
    pub fn new(config: PowerConfig) -> Self {
        let charge_wh = (config.initial_charge.clamp(0.0, 1.0) * config.capacity_wh).max(0.0);
        Self {
            config,
            charge_wh,
            clock: 0.0,
            asleep: false,
            totals: EnergyTotals::default(),
            mark: Default::default(),
        }
    }

    /// The parameters.
    pub fn config(&self) -> &PowerConfig {
        &self.config
    }

    /// Energy in the battery (Wh).
    pub fn charge_wh(&self) -> f64 {
        self.charge_wh
    }

    /// Energy totals since the start.
    pub fn totals(&self) -> EnergyTotals {
        self.totals
    }

    /// Puts the computer in (or out of) its sleep mode.
    pub fn set_asleep(&mut self, asleep: bool) {
        self.asleep = asleep;
    }

    /// `(a, b, w)`: `sin e = a + b cos H`, the hour angle `H = w (t - t_noon)` (rad, s).
    fn sky(&self) -> (f64, f64) {
        let c = &self.config;
        let delta = (MARS_OBLIQUITY_DEG.to_radians().sin() * c.ls_deg.to_radians().sin()).asin();
        let phi = c.latitude_deg.to_radians();
        (phi.sin() * delta.sin(), phi.cos() * delta.cos())
    }

    /// Hour angle at simulated time `t` (rad; 0 at local noon).
    fn hour_angle(&self, t: f64) -> f64 {
        (self.config.local_time_h - 12.0) / 24.0 * TAU + t / SOL_S * TAU
    }

    /// Panel output at full sun overhead (W).
    fn peak_w(&self) -> f64 {
        let c = &self.config;
        c.panel_area_m2 * c.panel_efficiency * c.irradiance_w_m2
    }

    /// Panel output at simulated time `t` (W).
    pub fn panel_w(&self, t: f64) -> f64 {
        let (a, b) = self.sky();
        self.peak_w() * (a + b * self.hour_angle(t).cos()).max(0.0)
    }

    /// Panel energy between simulated times `t0` and `t1` (Wh), in closed form.
    pub fn panel_energy_wh(&self, t0: f64, t1: f64) -> f64 {
        let (a, b) = self.sky();
        let g = |h: f64| clipped_integral(a, b, h);
        let joules_per_rad = SOL_S / TAU;
        self.peak_w() * (g(self.hour_angle(t1)) - g(self.hour_angle(t0))) * joules_per_rad / 3600.0
    }

    /// Drive motors' load (W) turning the wheels `wheels` metres (left, right) in `dt` seconds
    /// on a grade of `grade` (rad, positive uphill in the direction of travel).
    pub fn motors_w(&self, wheels: [f64; 2], dt: f64, grade: f64) -> f64 {
        if dt <= 0.0 {
            return 0.0;
        }
        let c = &self.config;
        let v = (0.5 * (wheels[0] + wheels[1]) / dt).abs();
        let diff = 0.5 * ((wheels[1] - wheels[0]) / dt).abs();
        let force_per_weight = (c.rolling_resistance + grade.sin().max(0.0)) * v + c.turn_resistance * diff;
        c.mass_kg * MARS_GRAVITY * force_per_weight / c.drive_efficiency.max(1e-6)
    }

    /// Runs the power system from its clock to `t` with the motors drawing `motors_w` and
    /// `images` camera images taken.
    pub fn advance(&mut self, t: f64, motors_w: f64, images: u32) {
        // NaN and going back in time are no time at all.
        let dt = if t > self.clock { t - self.clock } else { 0.0 };
        if dt == 0.0 && images == 0 {
            return;
        }
        let panel = self.panel_energy_wh(self.clock, self.clock + dt);
        let computer = if self.asleep { self.config.sleep_w } else { self.config.computer_w } * dt / 3600.0;
        let motors = motors_w.max(0.0) * dt / 3600.0;
        let cameras = self.config.camera_j_per_image * f64::from(images) / 3600.0;
        let t = &mut self.totals;
        t.panel_wh += panel;
        t.computer_wh += computer;
        t.motors_wh += motors;
        t.cameras_wh += cameras;
        let charge = self.charge_wh + panel - computer - motors - cameras;
        let full = self.config.capacity_wh.max(0.0);
        if charge > full {
            t.shunted_wh += charge - full;
        } else if charge < 0.0 {
            t.unmet_wh -= charge;
        }
        self.charge_wh = charge.clamp(0.0, full);
        self.clock += dt;
    }

    /// The reading at the end of a command (loads averaged since the previous reading), and
    /// the start of the next command's averages.
    pub fn reading(&mut self) -> PowerReading {
        let (before, since) = self.mark;
        let span = self.clock - since;
        let mean = |now: f64, then: f64| if span > 0.0 { (now - then) * 3600.0 / span } else { 0.0 };
        let t = self.totals;
        self.mark = (t, self.clock);
        let full = self.config.capacity_wh;
        PowerReading {
            t: self.clock,
            state_of_charge: if full > 0.0 { self.charge_wh / full } else { 0.0 },
            battery_wh: self.charge_wh,
            panel_w: self.panel_w(self.clock),
            computer_w: mean(t.computer_wh, before.computer_wh),
            motors_w: mean(t.motors_wh, before.motors_wh),
            cameras_w: mean(t.cameras_wh, before.cameras_wh),
        }
    }
}

/// `int max(0, a + b cos h) dh` from a sunless reference, continuous and increasing in `h`
/// (rad): whole periods count a full day each.
fn clipped_integral(a: f64, b: f64, h: f64) -> f64 {
    // Half the daylight arc: the hour angle of sunset (0 no sun, pi no night).
    let h0 = if b <= a.abs() { if a > 0.0 { PI } else { 0.0 } } else { (-a / b).clamp(-1.0, 1.0).acos() };
    let day = 2.0 * (a * h0 + b * h0.sin());
    let k = ((h + PI) / TAU).floor();
    let r = h - k * TAU; // in [-pi, pi)
    let part = if r <= -h0 {
        0.0
    } else if r >= h0 {
        day
    } else {
        a * (r + h0) + b * (r.sin() + h0.sin())
    };
    k * day + part
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Sun;

    fn model(local_time_h: f64, latitude_deg: f64, ls_deg: f64) -> PowerModel {
        PowerModel::new(PowerConfig { local_time_h, latitude_deg, ls_deg, ..PowerConfig::default() })
    }

    #[test]
    fn panel_output_follows_the_sine_of_the_sun_s_elevation_and_is_zero_at_night() {
        for (lat, ls) in [(-4.6, 0.0), (40.0, 90.0), (-70.0, 270.0), (80.0, 90.0)] {
            let m = model(0.0, lat, ls);
            for i in 0..96 {
                let t = f64::from(i) * SOL_S / 96.0;
                // The sun of the renderer, from its own formula.
                let e = Sun::on_mars(f64::from(i) / 4.0, lat, ls).elevation;
                let expected = if e > 0.0 { 0.4 * 0.2 * 500.0 * e.sin() } else { 0.0 };
                assert!((m.panel_w(t) - expected).abs() < 1e-9, "lat {lat} ls {ls} t {t}: {}", m.panel_w(t));
            }
        }
    }

    #[test]
    fn panel_energy_in_closed_form_matches_quadrature_across_sunrise_sunset_and_days() {
        for (start_h, lat, ls, span) in [
            (5.0, -4.6, 0.0, 3.0 * 3600.0),
            (16.0, 30.0, 60.0, 40_000.0),
            (0.0, 10.0, 0.0, 2.5 * SOL_S),
            (11.0, 80.0, 90.0, SOL_S),
        ] {
            let m = model(start_h, lat, ls);
            let t0 = 123.0;
            let n = 200_000;
            let step = span / f64::from(n);
            // Midpoint rule on the renderer's sun.
            let quad: f64 = (0..n)
                .map(|i| {
                    let t = t0 + (f64::from(i) + 0.5) * step;
                    let e = Sun::on_mars(start_h + t / (SOL_S / 24.0), lat, ls).elevation;
                    40.0 * e.sin().max(0.0) * step
                })
                .sum::<f64>()
                / 3600.0;
            let closed = m.panel_energy_wh(t0, t0 + span);
            assert!((closed - quad).abs() < 1e-6 * quad.max(1.0), "{start_h} {lat}: {closed} vs {quad}");
        }
    }

    #[test]
    fn the_battery_changes_by_panel_energy_minus_loads_and_stays_within_its_capacity() {
        let mut m = PowerModel::new(PowerConfig { initial_charge: 0.5, ..PowerConfig::default() });
        m.advance(100.0, 0.0, 0);
        let motors = m.motors_w([1.0, 1.0], 10.0, 0.0);
        // 20 kg * 3.711 * 0.15 * 0.1 m/s / 0.3.
        assert!((motors - 20.0 * 3.711 * 0.15 * 0.1 / 0.3).abs() < 1e-12);
        m.advance(110.0, motors, 0);
        m.advance(115.0, 0.0, 4);
        let expected = 75.0 + m.panel_energy_wh(0.0, 115.0)
            - 12.0 * 115.0 / 3600.0
            - motors * 10.0 / 3600.0
            - 4.0 * 5.0 / 3600.0;
        assert!((m.charge_wh() - expected).abs() < 1e-12);
        let r = m.reading();
        assert!((r.cameras_w - 20.0 / 115.0).abs() < 1e-12 && (r.computer_w - 12.0).abs() < 1e-12);
        assert!((r.state_of_charge - expected / 150.0).abs() < 1e-12);
        // A sol asleep fills it; the surplus is shunted.
        m.set_asleep(true);
        for i in 2..1480 {
            m.advance(f64::from(i) * 60.0, 0.0, 0);
        }
        assert!(m.charge_wh() <= 150.0 && m.totals().shunted_wh > 0.0);
        // A night of a heavy load empties it; the rest is unmet.
        let mut m = PowerModel::new(PowerConfig { local_time_h: 20.0, ..PowerConfig::default() });
        m.advance(10.0 * 3600.0, 50.0, 0);
        assert_eq!(m.charge_wh(), 0.0);
        assert!(m.totals().unmet_wh > 0.0);
    }
}
