//! Sleep and wake on the battery's charge: SR2's power management (paper 001 section 3: "the
//! system could switch to SLEEP mode if the battery voltage was too low and wake up when the
//! battery is charged").
//!
//! The executive sees power only as the platform's readings ([`PowerReading`] in each sensor
//! frame). Below `sleep_below` of charge the deliberative layer puts the rover to sleep: the
//! navigator stands by (no drives, no pictures), the platform holds in its sleep mode, and every
//! `check_s` seconds the rover wakes for one reading; at or above `wake_above` it wakes and the
//! plan goes on where it stopped. Sleep is mission time: the time budget keeps running.
//!
//! Departure: SR2 switched on battery voltage; here the platform's fuel gauge (state of charge)
//! is the reading, since the paper gives no voltage-charge curve for its battery.

use rovernav_core::PowerReading;
use serde::{Deserialize, Serialize};

/// When to sleep and wake (the mission's `[power]` thresholds).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PowerPolicy {
    /// Sleep when the state of charge falls below this (0..1).
    pub sleep_below: f64,
    /// Wake when it reaches this (0..1).
    pub wake_above: f64,
    /// Time between readings while asleep (s).
    pub check_s: f64,
}

impl Default for PowerPolicy {
    /// Sleep below 20 %, wake at 60 %, a reading a minute.
    fn default() -> Self {
        Self { sleep_below: 0.2, wake_above: 0.6, check_s: 60.0 }
    }
}

/// What the deliberative layer does about power this step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SleepAction {
    /// Nothing: awake and charged enough.
    Awake,
    /// Fall asleep now and hold, asleep, until the given time (s).
    Sleep(f64),
    /// Stay asleep until the given time (s).
    StayAsleep(f64),
    /// Wake up and go on.
    Wake,
}

/// Power in the run's report.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, schemars::JsonSchema)]
pub struct PowerReport {
    /// State of charge at the end (0..1).
    pub final_state_of_charge: f64,
    /// Lowest state of charge read (0..1).
    pub min_state_of_charge: f64,
    /// Energy in the battery at the end (Wh).
    pub battery_wh: f64,
    /// Times the rover went to sleep.
    pub sleeps: u32,
    /// Simulated time spent asleep (s).
    pub time_asleep_s: f64,
}

/// The sleep state machine on the platform's power readings.
#[derive(Clone, Debug)]
pub struct SleepMonitor {
    policy: PowerPolicy,
    last: Option<PowerReading>,
    min_soc: f64,
    asleep_since: Option<f64>,
    sleeps: u32,
    time_asleep_s: f64,
}

impl SleepMonitor {
    /// A monitor applying `policy`.
    pub fn new(policy: PowerPolicy) -> Self {
        Self { policy, last: None, min_soc: f64::INFINITY, asleep_since: None, sleeps: 0, time_asleep_s: 0.0 }
    }

    /// Takes a reading.
    pub fn on_reading(&mut self, reading: &PowerReading) {
        if reading.state_of_charge.is_finite() {
            self.min_soc = self.min_soc.min(reading.state_of_charge);
            self.last = Some(*reading);
        }
    }

    /// Whether the rover is asleep.
    pub fn asleep(&self) -> bool {
        self.asleep_since.is_some()
    }

    /// The last reading.
    pub fn last(&self) -> Option<&PowerReading> {
        self.last.as_ref()
    }

    /// What to do at simulated time `now` (s) on the last reading.
    pub fn decide(&mut self, now: f64) -> SleepAction {
        let Some(r) = self.last else { return SleepAction::Awake };
        let until = now + self.policy.check_s;
        match self.asleep_since {
            None if r.state_of_charge < self.policy.sleep_below => {
                self.asleep_since = Some(now);
                self.sleeps += 1;
                SleepAction::Sleep(until)
            }
            None => SleepAction::Awake,
            Some(since) if r.state_of_charge >= self.policy.wake_above => {
                self.time_asleep_s += now - since;
                self.asleep_since = None;
                SleepAction::Wake
            }
            Some(_) => SleepAction::StayAsleep(until),
        }
    }

    /// The report's power figures at simulated time `now` (none without a reading).
    pub fn report(&self, now: f64) -> Option<PowerReport> {
        let r = self.last?;
        let ongoing = self.asleep_since.map_or(0.0, |since| (now - since).max(0.0));
        Some(PowerReport {
            final_state_of_charge: r.state_of_charge,
            min_state_of_charge: self.min_soc,
            battery_wh: r.battery_wh,
            sleeps: self.sleeps,
            time_asleep_s: self.time_asleep_s + ongoing,
        })
    }
}

/// The run's message with its sleep, when the rover slept.
pub fn with_sleep(message: String, power: Option<&PowerReport>) -> String {
    match power {
        Some(p) if p.sleeps > 0 => {
            format!("{message}; asleep {:.0} s in {} sleep(s) waiting for charge", p.time_asleep_s, p.sleeps)
        }
        _ => message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(t: f64, soc: f64) -> PowerReading {
        PowerReading { t, state_of_charge: soc, ..Default::default() }
    }

    #[test]
    fn sleeps_below_the_low_threshold_and_wakes_only_at_the_high_one() {
        let mut m = SleepMonitor::new(PowerPolicy { sleep_below: 0.2, wake_above: 0.6, check_s: 60.0 });
        assert_eq!(m.decide(0.0), SleepAction::Awake, "no reading yet");
        m.on_reading(&at(10.0, 0.25));
        assert_eq!(m.decide(10.0), SleepAction::Awake);
        m.on_reading(&at(20.0, 0.19));
        assert_eq!(m.decide(20.0), SleepAction::Sleep(80.0));
        // Between the thresholds: asleep stays asleep (hysteresis).
        m.on_reading(&at(80.0, 0.4));
        assert_eq!(m.decide(80.0), SleepAction::StayAsleep(140.0));
        assert_eq!(m.report(110.0).unwrap().time_asleep_s, 90.0);
        m.on_reading(&at(140.0, 0.6));
        assert_eq!(m.decide(140.0), SleepAction::Wake);
        m.on_reading(&at(150.0, 0.5));
        assert_eq!(m.decide(150.0), SleepAction::Awake);
        let r = m.report(150.0).unwrap();
        assert_eq!((r.sleeps, r.time_asleep_s, r.min_state_of_charge), (1, 120.0, 0.19));
        assert!(
            with_sleep("reached".into(), Some(&r)).ends_with("asleep 120 s in 1 sleep(s) waiting for charge")
        );
        assert_eq!(with_sleep("reached".into(), None), "reached");
    }
}
