//! A navigator run in shadow beside the one that drives: the "no update" checkout of paper 003
//! section 6, generalised.
//!
//! Before Field D* was allowed to steer Opportunity, it was checked out in a mode where it
//! computed and logged its plan at every step without influencing the drive. Here any
//! registered navigator can ride along that way (mission field `shadow_navigator`): it gets the
//! same leg, the same frames and the same pose estimates as the driving navigator, its plan and
//! the command it would have given are published on `/navigation/shadow` each step, and the
//! report counts how often it agreed with the driver. Nothing it says reaches the motion
//! controller, so the drive is the driving navigator's alone, bit for bit.
//!
//! Departure from the paper: the shadow sees only what the driving navigator chose to sense
//! (its own sensing requests are logged, not executed), as a checkout on the real rover would.
//! The shadow's compute runs inside the navigator component's step, so a run with a shadow
//! reports its navigation time (`compute_per_cycle.navigation_s`) with the shadow's included.

use crate::messages::CommandMsg;
use rovernav_core::{NavCommand, NavInput, Navigator, Point2, RoverConfig};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// What the shadow navigator would have done at one step of the driving navigator.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ShadowMsg {
    /// The drive task (leg) both navigators work on.
    pub task: u64,
    /// The shadow navigator's registry name.
    pub navigator: String,
    /// The command it would have given.
    pub command: CommandMsg,
    /// Whether the driving navigator gave the same command.
    pub agrees: bool,
    /// Its plan (world frame, [x, y]), when it changed since its last step.
    pub plan: Option<Vec<[f64; 2]>>,
}

/// The shadow navigator's record over a run, for the report.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ShadowReport {
    /// The shadow navigator's registry name.
    pub navigator: String,
    /// Steps it took (one per driving-navigator step while its leg was open).
    pub steps: u64,
    /// Steps at which its command equalled the driving navigator's.
    pub agreeing_steps: u64,
    /// Plans it announced.
    pub plans: u64,
    /// How its last leg ended for it (`reached`, `unreachable`, ...), if it finished one.
    pub outcome: Option<String>,
}

/// A navigator in shadow: stepped with the driving navigator's inputs, never obeyed.
pub struct ShadowNavigator {
    name: String,
    rover: RoverConfig,
    navigator: Box<dyn Navigator>,
    /// The current leg is over for the shadow (it finished it).
    finished: bool,
    last_plan: Vec<Point2>,
    report: ShadowReport,
}

impl ShadowNavigator {
    /// A shadow running registered navigator `name` (with its default parameters).
    pub fn new(name: &str, rover: &RoverConfig) -> Result<Self, String> {
        let navigator = Self::build(name, rover)?;
        let report = ShadowReport { navigator: name.to_string(), ..ShadowReport::default() };
        Ok(Self {
            name: name.to_string(),
            rover: rover.clone(),
            navigator,
            finished: false,
            last_plan: Vec::new(),
            report,
        })
    }

    fn build(name: &str, rover: &RoverConfig) -> Result<Box<dyn Navigator>, String> {
        rovernav_navigation::navigator_with_params(name, rover, &Default::default())
            .map_err(|e| format!("shadow_navigator: {e}"))
    }

    /// A new leg: a fresh instance, as the driving navigator gets one.
    pub fn new_leg(&mut self) -> Result<(), String> {
        self.navigator = Self::build(&self.name, &self.rover)?;
        self.finished = false;
        self.last_plan.clear();
        Ok(())
    }

    /// Steps the shadow on the driving navigator's input; what it would have done, unless it
    /// has finished the leg already.
    pub fn step(&mut self, task: u64, input: &NavInput<'_>, driven: &NavCommand) -> Option<ShadowMsg> {
        if self.finished {
            return None;
        }
        let command = self.navigator.step(input);
        let agrees = command == *driven;
        self.report.steps += 1;
        self.report.agreeing_steps += u64::from(agrees);
        if let NavCommand::Finish(outcome, _) = &command {
            self.finished = true;
            self.report.outcome = Some(outcome.as_str().to_string());
        }
        let plan = self.navigator.planned_path();
        let plan = (plan != self.last_plan).then(|| {
            self.report.plans += 1;
            self.last_plan = plan;
            self.last_plan.iter().map(|p| [p.x, p.y]).collect()
        });
        Some(ShadowMsg { task, navigator: self.name.clone(), command, agrees, plan })
    }

    /// Its record so far.
    pub fn report(&self) -> &ShadowReport {
        &self.report
    }
}
