//! The campaign file (TOML): which navigators, how many procedural yards and how they vary, and
//! which real-DEM missions to add.
//!
//! Unknown fields are rejected (as in mission files) so that a misspelt key is an error naming
//! the key and its line rather than a silently ignored setting. Defaults not given in the file
//! come from the built-in default mission, so a campaign's yard is the default yard unless the
//! file says otherwise.

use crate::CampaignError;
use rovernav_executive::Mission;
use rovernav_executive::mission::TerrainSpec;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The built-in campaign (`campaigns/default.toml`), used when no campaign file is given.
pub const DEFAULT_CAMPAIGN_TOML: &str = include_str!("../../../campaigns/default.toml");

/// A campaign: N procedural yards plus DEM missions, each driven by every listed navigator.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CampaignSpec {
    /// Name (the default output folder is `out/campaign-<name>`).
    #[serde(default = "default_name")]
    pub name: String,
    /// Campaign seed: every trial's draws, and its terrain seed unless `first_terrain_seed` is
    /// given, derive from it.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Number of procedural yards.
    #[serde(default = "default_trials")]
    pub trials: usize,
    /// Terrain seed of the first yard, the next yard taking the next seed, instead of seeds
    /// drawn from the campaign seed: with the default yard, trial k is then the yard of
    /// `rovernav run --seed <first_terrain_seed + k>` (the yard's draws still come from the
    /// campaign seed).
    #[serde(default)]
    pub first_terrain_seed: Option<u64>,
    /// Navigator registry names, or `["all"]` for every registered combination; an entry may
    /// also choose options, `{ navigator = "gestalt", global_planner = "field-dstar" }`, read as
    /// the combination's name (`gestalt+field-dstar`).
    #[serde(default = "default_navigators", deserialize_with = "navigator_names_or_choices")]
    pub navigators: Vec<String>,
    /// Parameters per navigator (`[navigator_params.<name>]`, as a mission's
    /// `[navigator_params]`); a navigator without an entry keeps its defaults.
    #[serde(default)]
    pub navigator_params: std::collections::BTreeMap<String, rovernav_navigation::NavigatorParams>,
    /// Sensor overrides of every run (`[sensors]`, as a mission's; on a DEM mission they take
    /// the place of the file's own where given).
    #[serde(default, skip_serializing_if = "rovernav_executive::mission::SensorSpec::is_empty")]
    pub sensors: rovernav_executive::mission::SensorSpec,
    /// Localiser registry name used by every run.
    #[serde(default = "default_localizer")]
    pub localizer: String,
    /// Mission time budget of each procedural run (s).
    #[serde(default = "default_time_limit")]
    pub time_limit_s: f64,
    /// Navigator cycle budget of each procedural run.
    #[serde(default = "default_max_cycles")]
    pub max_cycles: u64,
    /// How the procedural yards are made.
    #[serde(default)]
    pub yard: YardSpec,
    /// Missions on real elevation models added after the procedural yards.
    #[serde(default)]
    pub dem: Vec<DemEntry>,
    /// Fault drills (`[[faults]]`, as a mission's): trial k injects entry k mod n, so each
    /// kind meets trials/n yards. An entry without `at_cycle` or `at_time_s` strikes before the
    /// command drawn from `fault_cycle`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub faults: Vec<rovernav_executive::mission::FaultSpec>,
    /// The command before which a drill's fault strikes, drawn per trial.
    #[serde(default = "default_fault_cycle")]
    pub fault_cycle: Draw,
    /// Folder the campaign file was read from (DEM mission paths resolve against it first).
    #[serde(skip)]
    pub base_dir: Option<PathBuf>,
}

/// The procedural Mars yards. Values that vary take a [`Draw`].
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct YardSpec {
    /// Side of the square yard (m).
    pub size_m: f64,
    /// Height-grid resolution (m).
    pub resolution_m: f64,
    /// Golombek-Rapp rock abundance k.
    pub rock_abundance: Draw,
    /// Regional slope (deg).
    pub slope_deg: Draw,
    /// Amplitude of the fractal relief (m).
    pub relief_m: Draw,
    /// Craters per hectare with diameter at least 1 m (the terrain generator's default if absent).
    pub craters_per_hectare: Option<f64>,
    /// Start [x, y] (m); by default the default mission's start scaled to the yard size.
    pub start: Option<[f64; 2]>,
    /// Start heading, counter-clockwise from east (deg).
    pub start_yaw_deg: f64,
    /// Goal [x, y] (m); by default the default mission's goal scaled to the yard size.
    pub goal: Option<[f64; 2]>,
    /// Arrival tolerance (m).
    pub goal_tolerance_m: f64,
}

/// A value that is fixed, drawn from a list, or drawn uniformly from a range, per trial.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(untagged, expecting = "a number, a list of numbers to draw from, or a table { min = .., max = .. }")]
pub enum Draw {
    /// The same value for every trial.
    Fixed(f64),
    /// One of these values, drawn uniformly per trial.
    OneOf(Vec<f64>),
    /// Uniform in [min, max] per trial.
    Range(RangeSpec),
}

/// An inclusive range.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RangeSpec {
    /// Lower bound.
    pub min: f64,
    /// Upper bound.
    pub max: f64,
}

impl Draw {
    /// Every value this draw can give, for range checks (a range gives its two ends).
    fn extremes(&self) -> Vec<f64> {
        match self {
            Draw::Fixed(v) => vec![*v],
            Draw::OneOf(vs) => vs.clone(),
            Draw::Range(r) => vec![r.min, r.max],
        }
    }

    /// One value, drawn with `rng`.
    pub fn sample(&self, rng: &mut impl rand::Rng) -> f64 {
        match self {
            Draw::Fixed(v) => *v,
            Draw::OneOf(vs) => vs[rng.random_range(0..vs.len())],
            Draw::Range(r) if r.max > r.min => rng.random_range(r.min..=r.max),
            Draw::Range(r) => r.min,
        }
    }
}

/// A real-DEM mission run as part of the campaign.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DemEntry {
    /// Mission file: absolute, or relative to the campaign file's folder, else to the working
    /// directory.
    pub mission: PathBuf,
    /// Trials on this mission, each with its own seed (rocks added on the DEM and sensor noise).
    #[serde(default = "one")]
    pub trials: usize,
}

fn one() -> usize {
    1
}
fn default_name() -> String {
    "campaign".into()
}
fn default_seed() -> u64 {
    1
}
fn default_trials() -> usize {
    20
}
fn default_navigators() -> Vec<String> {
    vec!["all".into()]
}
/// One `navigators` entry: a name, or a navigator with its options.
#[derive(Deserialize)]
#[serde(untagged)]
enum NavigatorItem {
    /// A registry name.
    Name(String),
    /// A navigator under a chosen global planner.
    Choice {
        /// Registry name.
        navigator: String,
        /// The global planner.
        global_planner: Option<String>,
    },
}

/// The `navigators` list with option tables read as their combinations' names.
fn navigator_names_or_choices<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<String>, D::Error> {
    let items = Vec::<NavigatorItem>::deserialize(d)?;
    items
        .into_iter()
        .map(|item| match item {
            NavigatorItem::Name(name) => Ok(name),
            NavigatorItem::Choice { navigator, global_planner } => rovernav_navigation::registry()
                .navigator(&navigator, global_planner.as_deref())
                .map(|choice| choice.spec())
                .map_err(serde::de::Error::custom),
        })
        .collect()
}

fn default_fault_cycle() -> Draw {
    Draw::Range(RangeSpec { min: 3.0, max: 15.0 })
}

fn default_localizer() -> String {
    Mission::default_mission().localizer
}
fn default_time_limit() -> f64 {
    Mission::default_mission().time_limit_s
}
fn default_max_cycles() -> u64 {
    Mission::default_mission().max_cycles
}

impl Default for YardSpec {
    /// The default mission's yard.
    fn default() -> Self {
        let m = Mission::default_mission();
        let TerrainSpec::Procedural { size_m, resolution_m, rock_abundance, relief_m, slope_deg, .. } =
            m.terrain
        else {
            unreachable!("the built-in default mission is procedural")
        };
        Self {
            size_m,
            resolution_m,
            rock_abundance: Draw::Fixed(rock_abundance),
            slope_deg: Draw::Fixed(slope_deg),
            relief_m: Draw::Fixed(relief_m),
            craters_per_hectare: None,
            start: None,
            start_yaw_deg: m.start.yaw_deg,
            goal: None,
            goal_tolerance_m: m.goal.tolerance_m,
        }
    }
}

impl YardSpec {
    /// Start position: the given one, or the default mission's start scaled to this yard.
    pub fn start_xy(&self) -> [f64; 2] {
        self.start.unwrap_or_else(|| scaled_default(self.size_m, true))
    }

    /// Goal position: the given one, or the default mission's goal scaled to this yard.
    pub fn goal_xy(&self) -> [f64; 2] {
        self.goal.unwrap_or_else(|| scaled_default(self.size_m, false))
    }
}

/// The default mission's start or goal, scaled from its yard to a yard of side `size_m`.
fn scaled_default(size_m: f64, start: bool) -> [f64; 2] {
    let m = Mission::default_mission();
    let TerrainSpec::Procedural { size_m: base, .. } = m.terrain else {
        unreachable!("the built-in default mission is procedural")
    };
    let (x, y) = if start { (m.start.x, m.start.y) } else { (m.goal.x, m.goal.y) };
    let k = size_m / base;
    [x.unwrap_or(0.0) * k, y.unwrap_or(0.0) * k]
}

impl CampaignSpec {
    /// Parses campaign text; `origin` names the source in error messages.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self, CampaignError> {
        let spec: CampaignSpec = toml::from_str(text).map_err(|e| {
            let mut message = String::new();
            if let Some(span) = e.span() {
                let line = text[..span.start.min(text.len())].matches('\n').count() + 1;
                message.push_str(&format!("line {line}: "));
            }
            message.push_str(&e.message().replace('\n', " "));
            CampaignError::Parse { path: origin.into(), message }
        })?;
        // The field's line, as mission errors give it (rovernav_executive::mission::check).
        spec.validate(origin).map_err(|e| match e {
            CampaignError::Invalid { path, field, message } => {
                let message = match rovernav_executive::mission::check::line_of(text, &field) {
                    Some(line) => format!("line {line}: {message}"),
                    None => message,
                };
                CampaignError::Invalid { path, field, message }
            }
            other => other,
        })?;
        Ok(spec)
    }

    /// Reads and validates a campaign file.
    pub fn from_file(path: &Path) -> Result<Self, CampaignError> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| CampaignError::Io { path: shown.clone(), message: e.to_string() })?;
        let mut spec = Self::from_toml(&text, &shown)?;
        spec.base_dir = path.parent().map(Path::to_path_buf);
        Ok(spec)
    }

    /// The built-in campaign.
    pub fn builtin() -> Self {
        Self::from_toml(DEFAULT_CAMPAIGN_TOML, "built-in campaign").expect("the built-in campaign is valid")
    }

    /// The navigator names this campaign runs, with `all` expanded, in the given order.
    pub fn navigator_names(&self) -> Vec<String> {
        if self.navigators.iter().any(|n| n == "all") {
            return rovernav_navigation::navigator_names().iter().map(|s| s.to_string()).collect();
        }
        self.navigators.clone()
    }

    /// Checks every value; the error names the campaign source and the dotted field.
    pub fn validate(&self, origin: &str) -> Result<(), CampaignError> {
        let bad = |field: &str, message: String| {
            Err(CampaignError::Invalid { path: origin.into(), field: field.into(), message })
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if self.name.is_empty() || !self.name.chars().all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
        {
            return bad("name", "must be non-empty letters, digits, '-', '_' or '.'".into());
        }
        if self.trials > 100_000 {
            return bad("trials", "at most 100000 procedural yards".into());
        }
        // Seeds stay within 32 bits, as drawn ones do: exact in every JSON reader.
        if let Some(first) = self.first_terrain_seed
            && first.saturating_add(self.trials as u64) > u64::from(u32::MAX) + 1
        {
            return bad(
                "first_terrain_seed",
                format!("{first} + {} trials runs past the largest terrain seed {}", self.trials, u32::MAX),
            );
        }
        if self.navigators.is_empty() {
            return bad("navigators", "name at least one navigator (or \"all\")".into());
        }
        let registry = rovernav_navigation::registry();
        for name in &self.navigators {
            if name != "all"
                && let Err(e) = registry.navigator(name, None)
            {
                return bad("navigators", e.to_string().replace("(known: ", "(known: all, "));
            }
        }
        let names = self.navigator_names();
        for (i, name) in names.iter().enumerate() {
            if names[..i].contains(name) {
                return bad("navigators", format!("`{name}` is listed twice"));
            }
        }
        for (name, params) in &self.navigator_params {
            if !names.contains(name) {
                return bad(
                    &format!("navigator_params.{name}"),
                    format!("`{name}` is not among the campaign's navigators ({})", names.join(", ")),
                );
            }
            if let Err(e) = rovernav_navigation::check_params(name, params) {
                let field = match e.param() {
                    Some(param) => format!("navigator_params.{name}.{param}"),
                    None => format!("navigator_params.{name}"),
                };
                return bad(&field, e.to_string());
            }
        }
        if let Err((field, why)) = self.sensors.check() {
            return bad(&format!("sensors.{field}"), why.into());
        }
        if let Err(e) = registry.check_localizer(&self.localizer, &Default::default()) {
            return bad("localizer", e.to_string());
        }
        if let Err(why) = rovernav_executive::mission::check::positive_up_to(self.time_limit_s, 1.0e7, " s") {
            return bad("time_limit_s", why);
        }
        if self.max_cycles == 0 {
            return bad("max_cycles", "must be at least 1".into());
        }
        if let Err((field, why)) = rovernav_executive::mission::check_faults(&self.faults) {
            return bad(&field, why.into());
        }
        if self.fault_cycle.extremes().iter().any(|c| !(c.is_finite() && (0.0..=1.0e6).contains(c))) {
            return bad("fault_cycle", "must be command numbers in [0, 1000000]".into());
        }
        let y = &self.yard;
        if !positive(y.size_m) || y.size_m > 2000.0 {
            return bad("yard.size_m", "must be in (0, 2000] m".into());
        }
        if !positive(y.resolution_m) || y.resolution_m > y.size_m / 4.0 {
            return bad("yard.resolution_m", "must be positive and much smaller than the yard".into());
        }
        if (y.size_m / y.resolution_m).powi(2) > 1.0e8 {
            return bad("yard.resolution_m", "yard too large at this resolution (over 1e8 cells)".into());
        }
        check_draw(
            &y.rock_abundance,
            "yard.rock_abundance",
            origin,
            |v| (0.0..=0.5).contains(&v),
            "[0, 0.5]",
        )?;
        check_draw(&y.slope_deg, "yard.slope_deg", origin, |v| v.abs() < 45.0, "(-45, 45) deg")?;
        check_draw(&y.relief_m, "yard.relief_m", origin, |v| (0.0..=100.0).contains(&v), "[0, 100] m")?;
        // The checks a mission's fields get (rovernav_executive::mission::check).
        use rovernav_executive::mission::check;
        if let Some(c) = y.craters_per_hectare
            && let Err(why) = check::craters_per_hectare(c, y.size_m)
        {
            return bad("yard.craters_per_hectare", why);
        }
        // Keep the start and goal pads (radius 1 m) inside the yard.
        for (field, p) in [("yard.start", y.start_xy()), ("yard.goal", y.goal_xy())] {
            if !p.iter().all(|v| v.is_finite() && *v >= 1.0 && *v <= y.size_m - 1.0) {
                return bad(
                    field,
                    format!("({}, {}) must lie at least 1 m inside the {} m yard", p[0], p[1], y.size_m),
                );
            }
        }
        if !y.start_yaw_deg.is_finite() {
            return bad("yard.start_yaw_deg", "must be a finite number".into());
        }
        if let Err(why) = check::tolerance(y.goal_tolerance_m) {
            return bad("yard.goal_tolerance_m", why);
        }
        for (i, d) in self.dem.iter().enumerate() {
            if d.trials == 0 || d.trials > 10_000 {
                return bad(&format!("dem[{i}].trials"), "must be in [1, 10000]".into());
            }
        }
        if self.trials + self.dem.iter().map(|d| d.trials).sum::<usize>() == 0 {
            return bad("trials", "the campaign has no trial (no yards and no DEM missions)".into());
        }
        Ok(())
    }
}

fn check_draw(
    draw: &Draw,
    field: &str,
    origin: &str,
    ok: impl Fn(f64) -> bool,
    range: &str,
) -> Result<(), CampaignError> {
    let bad =
        |message: String| Err(CampaignError::Invalid { path: origin.into(), field: field.into(), message });
    match draw {
        Draw::OneOf(vs) if vs.is_empty() => return bad("the list is empty".into()),
        Draw::Range(r) if r.min > r.max => return bad(format!("min {} is above max {}", r.min, r.max)),
        _ => {}
    }
    for v in draw.extremes() {
        if !(v.is_finite() && ok(v)) {
            return bad(format!("{v} is outside {range}"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        CampaignSpec::from_toml(text, "c.toml").unwrap_err().to_string()
    }

    #[test]
    fn builtin_and_shipped_campaigns_parse() {
        let b = CampaignSpec::builtin();
        assert_eq!(b.navigator_names().len(), rovernav_navigation::navigator_names().len());
        for file in ["quick.toml", "full.toml", "default.toml", "roverbug-yard.toml"] {
            let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../campaigns").join(file);
            let spec = CampaignSpec::from_file(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(spec.trials > 0, "{file}");
        }
    }

    #[test]
    fn navigators_may_be_chosen_with_options_and_old_names_still_work() {
        let spec = CampaignSpec::from_toml(
            "navigators = [\"gestalt+field-dstar\", { navigator = \"grid\", global_planner = \"dstar-lite\" }, \"sr2+look-back\"]",
            "c.toml",
        )
        .unwrap();
        assert_eq!(spec.navigator_names(), ["gestalt+field-dstar", "mrpta", "sr2+look-back"]);
        let e = err("navigators = [{ navigator = \"gestalt\", global_planner = \"astar\" }]");
        assert!(e.contains("c.toml") && e.contains("no global planner `astar`"), "{e}");
        let e = err("navigators = [\"warp\"]");
        assert!(e.contains("known: all, grid, gestalt") && !e.contains('\n'), "{e}");
        let e = err("localizer = \"gps\"");
        assert!(e.contains("unknown localizer `gps`") && e.contains("ekf-ml-targets"), "{e}");
    }

    #[test]
    fn an_empty_file_is_the_default_yard() {
        let spec = CampaignSpec::from_toml("", "c.toml").unwrap();
        let m = Mission::default_mission();
        assert_eq!(spec.yard.start_xy(), [m.start.x.unwrap(), m.start.y.unwrap()]);
        assert_eq!(spec.yard.goal_xy(), [m.goal.x.unwrap(), m.goal.y.unwrap()]);
        assert_eq!(spec.localizer, m.localizer);
    }

    #[test]
    fn placement_scales_with_the_yard() {
        let spec = CampaignSpec::from_toml("[yard]\nsize_m = 12.0", "c.toml").unwrap();
        // The default mission puts start and goal at 1/6 and 2/3 of its 30 m side.
        assert!((spec.yard.start_xy()[0] - 2.0).abs() < 1e-12);
        assert!((spec.yard.goal_xy()[1] - 8.0).abs() < 1e-12);
    }

    #[test]
    fn draws_parse_in_three_forms() {
        let spec = CampaignSpec::from_toml(
            "[yard]\nrock_abundance = [0.05, 0.1]\nslope_deg = { min = 0, max = 5 }\nrelief_m = 0.2",
            "c.toml",
        )
        .unwrap();
        assert_eq!(spec.yard.rock_abundance, Draw::OneOf(vec![0.05, 0.1]));
        assert_eq!(spec.yard.slope_deg, Draw::Range(RangeSpec { min: 0.0, max: 5.0 }));
        assert_eq!(spec.yard.relief_m, Draw::Fixed(0.2));
    }

    #[test]
    fn misspelt_field_is_named_with_its_line() {
        let e = err("name = \"x\"\n[yard]\nrock_abundanse = 0.1\n");
        assert!(e.contains("c.toml") && e.contains("rock_abundanse") && e.contains("line 3"), "{e}");
    }

    #[test]
    fn invalid_values_name_the_field() {
        for (text, field) in [
            ("[yard]\nrock_abundance = [0.1, 0.9]", "yard.rock_abundance"),
            ("[yard]\nslope_deg = { min = 5, max = 1 }", "yard.slope_deg"),
            ("[yard]\nrelief_m = []", "yard.relief_m"),
            ("navigators = [\"warp-drive\"]", "navigators"),
            ("navigators = [\"nat\", \"nat\"]", "navigators"),
            ("localizer = \"gps\"", "localizer"),
            ("time_limit_s = -1.0", "time_limit_s"),
            ("[yard]\nsize_m = 10.0\ngoal = [9.5, 5.0]", "yard.goal"),
            ("trials = 0", "trials"),
            ("first_terrain_seed = 4294967290\ntrials = 7", "first_terrain_seed"),
            ("first_terrain_seed = 4294967295\ntrials = 2", "first_terrain_seed"),
            ("[[dem]]\nmission = \"m.toml\"\ntrials = 0", "dem[0].trials"),
            ("[yard]\ncraters_per_hectare = 1e9", "yard.craters_per_hectare"),
            ("[yard]\ngoal_tolerance_m = 1e308", "yard.goal_tolerance_m"),
            ("time_limit_s = nan", "time_limit_s"),
        ] {
            let e = err(text);
            assert!(e.contains("c.toml") && e.contains(&format!("`{field}`")), "{text}: {e}");
        }
    }

    #[test]
    fn invalid_values_give_their_line() {
        let e = err("name = \"x\"\n[yard]\ncraters_per_hectare = 1e9\n");
        assert!(e.contains("`yard.craters_per_hectare`: line 3: "), "{e}");
    }

    #[test]
    fn terrain_seeds_may_end_at_the_largest_32_bit_seed() {
        for text in
            ["first_terrain_seed = 4294967290\ntrials = 6", "first_terrain_seed = 4294967295\ntrials = 1"]
        {
            CampaignSpec::from_toml(text, "c.toml").unwrap_or_else(|e| panic!("{text}: {e}"));
        }
    }

    #[test]
    fn a_draw_of_the_wrong_shape_says_what_is_expected() {
        let e = err("[yard]\nslope_deg = \"steep\"");
        assert!(e.contains("line 2") && e.contains("a list of numbers"), "{e}");
    }

    #[test]
    fn sampling_stays_within_the_draw() {
        use rand::SeedableRng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let one_of = Draw::OneOf(vec![0.1, 0.2, 0.3]);
        let range = Draw::Range(RangeSpec { min: 2.0, max: 4.0 });
        for _ in 0..200 {
            assert!([0.1, 0.2, 0.3].contains(&one_of.sample(&mut rng)));
            let v = range.sample(&mut rng);
            assert!((2.0..=4.0).contains(&v));
        }
        assert_eq!(Draw::Fixed(1.5).sample(&mut rng), 1.5);
    }
}
