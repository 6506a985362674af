//! From a campaign spec to trials and jobs: each trial's terrain seed (unless the file gives the
//! seeds, `first_terrain_seed`) and draws come from its own random stream of the campaign seed,
//! so trial k is the same terrain whatever the trial count, the shard or the machine.

use crate::CampaignError;
use crate::spec::CampaignSpec;
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rovernav_executive::Mission;
use rovernav_executive::mission::{GoalSpec, PoseSpec, TerrainSpec};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// What a trial's terrain is.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum TerrainKind {
    /// A procedural Mars yard.
    Procedural,
    /// A mission on a real elevation model.
    Dem,
}

impl TerrainKind {
    /// The name used in rows and tables.
    pub fn as_str(self) -> &'static str {
        match self {
            TerrainKind::Procedural => "procedural",
            TerrainKind::Dem => "dem",
        }
    }
}

/// One terrain of the campaign and the values drawn for it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TrialInfo {
    /// Trial index (procedural yards first, then DEM missions).
    pub trial: usize,
    /// Terrain kind.
    pub terrain_kind: TerrainKind,
    /// `yard` or the DEM mission's name.
    pub terrain: String,
    /// Seed of the terrain and of every sensor's noise.
    pub seed: u64,
    /// Rock abundance k.
    pub rock_abundance: f64,
    /// Regional slope (deg), procedural yards only.
    pub slope_deg: Option<f64>,
    /// Relief amplitude (m), procedural yards only.
    pub relief_m: Option<f64>,
    /// Yard side (m), procedural yards only.
    pub size_m: Option<f64>,
    /// The fault drill's kind (`[[faults]]`), if the trial injects one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fault: Option<String>,
}

/// One run: a trial driven by one navigator. `index` is the position in the flattened
/// trial-major job list that shards slice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Job {
    /// Position in the flattened job list.
    pub index: usize,
    /// Trial position (= trial index).
    pub trial: usize,
    /// Navigator position in [`Plan::navigators`].
    pub navigator: usize,
}

/// A campaign made concrete: navigators, trials and the mission of each trial.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The spec, with command-line overrides applied.
    pub spec: CampaignSpec,
    /// Navigator names, `all` expanded.
    pub navigators: Vec<String>,
    /// The trials, by index.
    pub trials: Vec<TrialInfo>,
    /// One-line notes on DEM missions left out (missing DEM file).
    pub skipped: Vec<String>,
    /// The mission of each trial (its navigator is set per job).
    missions: Vec<(Mission, String)>,
}

/// Gives trial `k` its fault drill (entry k mod n of `[[faults]]`), striking before the command
/// drawn from `fault_cycle` unless the entry says when; returns its label (`silent_sensor:mast`). Draws nothing without
/// drills, so campaigns without them keep their yards.
fn assign_fault(
    spec: &CampaignSpec,
    k: usize,
    rng: &mut impl rand::Rng,
    mission: &mut Mission,
) -> Option<String> {
    if spec.faults.is_empty() {
        return None;
    }
    let mut fault = spec.faults[k % spec.faults.len()].clone();
    let cycle = spec.fault_cycle.sample(rng).round().max(0.0) as u64;
    if fault.at_cycle.is_none() && fault.at_time_s.is_none() {
        fault.at_cycle = Some(cycle);
    }
    let label = fault.label();
    mission.faults.push(fault);
    Some(label)
}

/// Stream of the procedural trials' draws; DEM trials use streams with the top bit set.
const DEM_STREAM: u64 = 1 << 63;

impl Plan {
    /// Draws every trial of `spec`. DEM missions whose DEM file is missing are skipped with a
    /// note in [`Plan::skipped`]; a missing or invalid mission file is an error.
    pub fn new(spec: CampaignSpec) -> Result<Self, CampaignError> {
        let navigators = spec.navigator_names();
        let mut trials = Vec::new();
        let mut missions = Vec::new();
        let y = &spec.yard;
        for k in 0..spec.trials {
            let mut rng = trial_rng(spec.seed, k as u64);
            // 32-bit seeds: exact in every JSON reader and short to type after `--seed`. Drawn
            // even when the file gives the seeds, so that the yard's draws stay the same.
            let drawn = u64::from(rng.next_u32());
            let seed = spec.first_terrain_seed.map_or(drawn, |first| first + k as u64);
            let rock_abundance = y.rock_abundance.sample(&mut rng);
            let slope_deg = y.slope_deg.sample(&mut rng);
            let relief_m = y.relief_m.sample(&mut rng);
            let mut mission = Mission::default_mission();
            mission.name = format!("{}-trial-{k:04}", spec.name);
            mission.seed = seed;
            mission.localizer = spec.localizer.clone();
            mission.sensors = spec.sensors.clone();
            mission.time_limit_s = spec.time_limit_s;
            mission.max_cycles = spec.max_cycles;
            mission.terrain = TerrainSpec::Procedural {
                size_m: y.size_m,
                resolution_m: y.resolution_m,
                rock_abundance,
                relief_m,
                slope_deg,
                craters_per_hectare: y.craters_per_hectare,
            };
            let [sx, sy] = y.start_xy();
            let [gx, gy] = y.goal_xy();
            mission.start =
                PoseSpec { x: Some(sx), y: Some(sy), yaw_deg: y.start_yaw_deg, ..Default::default() };
            mission.goal =
                GoalSpec { x: Some(gx), y: Some(gy), tolerance_m: y.goal_tolerance_m, ..Default::default() };
            trials.push(TrialInfo {
                trial: k,
                terrain_kind: TerrainKind::Procedural,
                terrain: "yard".into(),
                seed,
                rock_abundance,
                slope_deg: Some(slope_deg),
                relief_m: Some(relief_m),
                size_m: Some(y.size_m),
                fault: assign_fault(&spec, k, &mut rng, &mut mission),
            });
            missions.push((mission, format!("campaign `{}` trial {k}", spec.name)));
        }
        let mut skipped = Vec::new();
        for (e, entry) in spec.dem.iter().enumerate() {
            let path = resolve(spec.base_dir.as_deref(), &entry.mission);
            let template = Mission::from_file(&path).map_err(|err| CampaignError::Invalid {
                path: format!("campaign `{}`", spec.name),
                field: format!("dem[{e}].mission"),
                message: err.to_string(),
            })?;
            let TerrainSpec::Dem { path: dem_path, rock_abundance, .. } = &template.terrain else {
                return Err(CampaignError::Invalid {
                    path: format!("campaign `{}`", spec.name),
                    field: format!("dem[{e}].mission"),
                    message: format!("{}: terrain kind is not `dem`", path.display()),
                });
            };
            if !dem_exists(&template, dem_path) {
                skipped.push(format!(
                    "dem[{e}] ({}): skipped, DEM file `{}` not found (set ROVERNAV_DATA)",
                    entry.mission.display(),
                    dem_path.display()
                ));
                continue;
            }
            for r in 0..entry.trials {
                let k = trials.len();
                let mut rng = trial_rng(spec.seed, DEM_STREAM | ((e as u64) << 32) | r as u64);
                let mut mission = template.clone();
                mission.seed = u64::from(rng.next_u32());
                mission.localizer = spec.localizer.clone();
                mission.sensors = template.sensors.overridden_by(&spec.sensors);
                trials.push(TrialInfo {
                    trial: k,
                    terrain_kind: TerrainKind::Dem,
                    terrain: template.name.clone(),
                    seed: mission.seed,
                    rock_abundance: *rock_abundance,
                    slope_deg: None,
                    relief_m: None,
                    size_m: None,
                    fault: assign_fault(&spec, k, &mut rng, &mut mission),
                });
                missions.push((mission, format!("{} (campaign trial {k})", path.display())));
            }
        }
        if trials.is_empty() {
            return Err(CampaignError::Invalid {
                path: format!("campaign `{}`", spec.name),
                field: "dem".into(),
                message: format!("no trial left to run: {}", skipped.join("; ")),
            });
        }
        Ok(Self { spec, navigators, trials, skipped, missions })
    }

    /// Every (trial, navigator) job, trial-major.
    pub fn jobs(&self) -> Vec<Job> {
        let n = self.navigators.len();
        (0..self.trials.len() * n)
            .map(|index| Job { index, trial: index / n, navigator: index % n })
            .collect()
    }

    /// The mission of a job (its trial's mission with the job's navigator) and its origin label.
    pub fn mission(&self, job: &Job) -> (Mission, &str) {
        let (mission, origin) = &self.missions[job.trial];
        let mut mission = mission.clone();
        mission.navigator = self.navigators[job.navigator].clone();
        mission.navigator_params =
            self.spec.navigator_params.get(&mission.navigator).cloned().unwrap_or_default();
        (mission, origin)
    }

    /// The mission file text of a procedural trial, to rerun it with `rovernav run`.
    pub fn mission_toml(&self, trial: usize) -> Option<String> {
        let (m, _) = &self.missions[trial];
        let TerrainSpec::Procedural {
            size_m,
            resolution_m,
            rock_abundance,
            relief_m,
            slope_deg,
            craters_per_hectare,
        } = &m.terrain
        else {
            return None;
        };
        let craters = craters_per_hectare.map_or(String::new(), |c| format!("craters_per_hectare = {c:?}\n"));
        let nav = self.navigators.first().map_or("astar-grid", String::as_str);
        let params = match self.spec.navigator_params.get(nav) {
            Some(p) if !p.is_empty() => {
                let lines: String = p.iter().map(|(k, v)| format!("{k} = {v:?}\n")).collect();
                format!("\n[navigator_params]\n{lines}")
            }
            _ => String::new(),
        };
        Some(format!(
            "# Trial {trial} of campaign `{campaign}` (campaign seed {cseed}).\n\
             name = \"{name}\"\nseed = {seed}\nnavigator = \"{nav}\"\nlocalizer = \"{loc}\"\n\
             time_limit_s = {tl:?}\nmax_cycles = {mc}\n\n\
             [terrain]\nkind = \"procedural\"\nsize_m = {size_m:?}\nresolution_m = {resolution_m:?}\n\
             rock_abundance = {rock_abundance:?}\nrelief_m = {relief_m:?}\nslope_deg = {slope_deg:?}\n{craters}\n\
             [start]\nx = {sx:?}\ny = {sy:?}\nyaw_deg = {yaw:?}\n\n\
             [goal]\nx = {gx:?}\ny = {gy:?}\ntolerance_m = {tol:?}\n{sensors}{params}{faults}",
            sensors = m.sensors.toml_table(),
            faults = m
                .faults
                .iter()
                .map(|f| format!("\n[[faults]]\n{}", toml::to_string(f).unwrap_or_default()))
                .collect::<String>(),
            campaign = self.spec.name,
            cseed = self.spec.seed,
            name = m.name,
            seed = m.seed,
            loc = m.localizer,
            tl = m.time_limit_s,
            mc = m.max_cycles,
            sx = m.start.x.unwrap_or_default(),
            sy = m.start.y.unwrap_or_default(),
            yaw = m.start.yaw_deg,
            gx = m.goal.x.unwrap_or_default(),
            gy = m.goal.y.unwrap_or_default(),
            tol = m.goal.tolerance_m,
        ))
    }
}

/// The random stream of one trial.
fn trial_rng(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

/// A campaign-relative path: absolute, else relative to the campaign file's folder when it
/// exists there, else as given (relative to the working directory).
fn resolve(base: Option<&Path>, path: &Path) -> PathBuf {
    if path.is_absolute() {
        return path.to_path_buf();
    }
    if let Some(base) = base {
        let p = base.join(path);
        if p.exists() {
            return p;
        }
    }
    path.to_path_buf()
}

/// Whether a DEM mission's file can be found the way the executive looks for it (absolute,
/// relative to the mission file, or relative to `ROVERNAV_DATA`).
fn dem_exists(mission: &Mission, dem: &Path) -> bool {
    if dem.is_absolute() {
        return dem.is_file();
    }
    mission.base_dir.as_ref().is_some_and(|b| b.join(dem).is_file())
        || rovernav_core::data_dir().join(dem).is_file()
}

/// A slice of the flattened job list: shard `index` of `count` (1-based) runs the jobs whose
/// position is `index - 1` modulo `count`, so slices are disjoint, cover every job and get
/// trials of every kind.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct Shard {
    /// 1-based slice number.
    pub index: usize,
    /// Number of slices.
    pub count: usize,
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// Whether this slice runs job `index`.
    pub fn contains(&self, job_index: usize) -> bool {
        job_index % self.count == self.index - 1
    }

    /// A checked shard; `source_name` names the option or variable in errors.
    pub fn new(index: usize, count: usize, source_name: &str) -> Result<Self, CampaignError> {
        if count == 0 || index == 0 || index > count {
            return Err(CampaignError::Shard {
                source_name: source_name.into(),
                message: format!("shard {index}/{count}: need 1 <= i <= n (i counts from 1)"),
            });
        }
        Ok(Self { index, count })
    }

    /// Parses `i/n` (1-based `i`), as given to `--shard`.
    pub fn parse(text: &str) -> Result<Self, CampaignError> {
        let bad = || CampaignError::Shard {
            source_name: "--shard".into(),
            message: format!("`{text}` is not i/n (e.g. 2/4: the second of four slices)"),
        };
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let i = i.trim().parse().map_err(|_| bad())?;
        let n = n.trim().parse().map_err(|_| bad())?;
        Self::new(i, n, "--shard")
    }

    /// The slice a job-array scheduler assigned, if any. Slurm: `SLURM_ARRAY_TASK_ID` with
    /// `SLURM_ARRAY_TASK_COUNT`, `SLURM_ARRAY_TASK_MIN` and `SLURM_ARRAY_TASK_STEP` (so
    /// `--array=0-3`, `--array=1-4` and `--array=0-12:4` all work). Kubernetes indexed jobs:
    /// the 0-based `JOB_COMPLETION_INDEX` with the count from `count` (`--shard-count`) or
    /// `ROVERNAV_SHARD_COUNT`. `count`, when given, also overrides Slurm's count.
    pub fn from_env(
        var: impl Fn(&str) -> Option<String>,
        count: Option<usize>,
    ) -> Result<Option<Self>, CampaignError> {
        let number = |name: &str| -> Result<Option<usize>, CampaignError> {
            var(name)
                .map(|v| {
                    v.trim().parse::<usize>().map_err(|_| CampaignError::Shard {
                        source_name: name.into(),
                        message: format!("`{v}` is not a non-negative integer"),
                    })
                })
                .transpose()
        };
        let need_count = |name: &str, hint: &str| -> Result<usize, CampaignError> {
            match count {
                Some(c) => Ok(c),
                None => number(hint)?.ok_or_else(|| CampaignError::Shard {
                    source_name: name.into(),
                    message: format!("is set but {hint} (or --shard-count) is not"),
                }),
            }
        };
        if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
            let n = need_count("SLURM_ARRAY_TASK_ID", "SLURM_ARRAY_TASK_COUNT")?;
            let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let step = number("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
            if id < min || (id - min) % step != 0 {
                return Err(CampaignError::Shard {
                    source_name: "SLURM_ARRAY_TASK_ID".into(),
                    message: format!("{id} is not in the array {min}, {}, ...", min + step),
                });
            }
            return Self::new((id - min) / step + 1, n, "SLURM_ARRAY_TASK_ID").map(Some);
        }
        if let Some(idx) = number("JOB_COMPLETION_INDEX")? {
            let n = need_count("JOB_COMPLETION_INDEX", "ROVERNAV_SHARD_COUNT")?;
            return Self::new(idx + 1, n, "JOB_COMPLETION_INDEX").map(Some);
        }
        Ok(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn spec(text: &str) -> CampaignSpec {
        CampaignSpec::from_toml(text, "c.toml").unwrap()
    }

    #[test]
    fn sensor_overrides_reach_every_run_and_its_trial_file() {
        let p = Plan::new(spec("trials = 2\n[sensors]\nstereo_noise_scale = 0.5")).unwrap();
        for job in p.jobs() {
            assert_eq!(p.mission(&job).0.sensors.stereo_noise_scale, Some(0.5));
        }
        let file = p.mission_toml(1).expect("a procedural trial");
        let rerun = Mission::from_toml(&file, "trial.toml").unwrap();
        assert_eq!(rerun.sensors, p.mission(&p.jobs()[p.navigators.len()]).0.sensors);
        let err =
            CampaignSpec::from_toml("[sensors]\nstereo_dropout = 2.0", "c.toml").unwrap_err().to_string();
        assert!(err.contains("sensors.stereo_dropout"), "{err}");
    }

    #[test]
    fn a_trial_is_the_same_whatever_the_trial_count() {
        let a = Plan::new(spec("trials = 3\n[yard]\nrock_abundance = [0.05, 0.1, 0.2]")).unwrap();
        let b = Plan::new(spec("trials = 8\n[yard]\nrock_abundance = [0.05, 0.1, 0.2]")).unwrap();
        assert_eq!(a.trials[..], b.trials[..3]);
        let seeds: std::collections::BTreeSet<u64> = b.trials.iter().map(|t| t.seed).collect();
        assert_eq!(seeds.len(), 8, "every trial has its own terrain seed");
    }

    #[test]
    fn first_terrain_seed_gives_the_yards_of_the_run_command() {
        let p = Plan::new(spec("first_terrain_seed = 7\ntrials = 3\nnavigators = [\"roverbug\"]")).unwrap();
        assert_eq!(p.trials.iter().map(|t| t.seed).collect::<Vec<_>>(), [7, 8, 9]);
        // `rovernav run --seed 8` runs the default mission with seed 8.
        let mut run = Mission::default_mission();
        run.seed = 8;
        let (mut m, _) = p.mission(&p.jobs()[1]);
        // Only the name (in the report) and the navigator (`--navigator roverbug`) differ.
        (m.name, run.navigator) = (run.name.clone(), "roverbug".into());
        assert_eq!(m, run);
        // The yard's draws do not depend on where the seeds come from.
        let yard = "trials = 3\n[yard]\nslope_deg = { min = 0.0, max = 6.0 }";
        let drawn = Plan::new(spec(yard)).unwrap();
        let given = Plan::new(spec(&format!("first_terrain_seed = 7\n{yard}"))).unwrap();
        let slopes = |p: &Plan| p.trials.iter().map(|t| t.slope_deg).collect::<Vec<_>>();
        assert_eq!(slopes(&drawn), slopes(&given));
        assert!(slopes(&given).windows(2).all(|w| w[0] != w[1]), "drawn per trial");
    }

    #[test]
    fn navigator_params_go_to_their_navigator_s_runs_and_trial_files() {
        let p = Plan::new(spec(
            "trials = 1\nnavigators = [\"roverbug\", \"nat\"]\n[navigator_params.roverbug]\nmax_wedges = 50\nsafety_clearance_margin = 0.8",
        ))
        .unwrap();
        let jobs = p.jobs();
        let (bug, _) = p.mission(&jobs[0]);
        let (nat, _) = p.mission(&jobs[1]);
        assert_eq!(
            bug.navigator_params,
            [("max_wedges".into(), 50.0), ("safety_clearance_margin".into(), 0.8)].into()
        );
        assert!(nat.navigator_params.is_empty());
        let back = Mission::from_toml(&p.mission_toml(0).unwrap(), "trial.toml").unwrap();
        assert_eq!(back, bug);
        for (bad, field) in [
            ("[navigator_params.sr2]\nleg_m = 2.0", "navigator_params.sr2"),
            ("[navigator_params.roverbug]\nwedges = 2", "navigator_params.roverbug.wedges"),
            ("[navigator_params.roverbug]\nmax_steps = -3", "navigator_params.roverbug.max_steps"),
        ] {
            let text = format!("trials = 1\nnavigators = [\"roverbug\"]\n{bad}");
            let err = CampaignSpec::from_toml(&text, "c.toml").unwrap_err().to_string();
            assert!(err.contains("c.toml") && err.contains(field), "{field}: {err}");
        }
    }

    #[test]
    fn another_campaign_seed_draws_other_terrains() {
        let a = Plan::new(spec("seed = 1\ntrials = 4")).unwrap();
        let b = Plan::new(spec("seed = 2\ntrials = 4")).unwrap();
        assert!(a.trials.iter().zip(&b.trials).all(|(x, y)| x.seed != y.seed));
    }

    #[test]
    fn missions_carry_the_draws_and_the_navigator() {
        let p =
            Plan::new(spec("trials = 2\nnavigators = [\"nat\", \"sr2\"]\n[yard]\nsize_m = 12.0")).unwrap();
        let jobs = p.jobs();
        assert_eq!(jobs.len(), 4);
        let (m, _) = p.mission(&jobs[3]);
        assert_eq!((m.navigator.as_str(), m.seed), ("sr2", p.trials[1].seed));
        let TerrainSpec::Procedural { size_m, rock_abundance, .. } = m.terrain else { panic!() };
        assert_eq!((size_m, rock_abundance), (12.0, p.trials[1].rock_abundance));
        // The mission text reruns the same trial.
        let text = p.mission_toml(1).unwrap();
        let mut back = Mission::from_toml(&text, "trial.toml").unwrap();
        back.navigator = "sr2".into();
        assert_eq!(back, m);
    }

    #[test]
    fn a_missing_dem_is_skipped_with_a_note() {
        let dir = std::env::temp_dir().join(format!("rovernav-campaign-plan-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mission = include_str!("../../../missions/gale-traverse.toml")
            .replace("gale/missionDEM.tif", "/nonexistent/none.tif");
        std::fs::write(dir.join("m.toml"), mission).unwrap();
        let mut s = spec("trials = 1\n[[dem]]\nmission = \"m.toml\"\ntrials = 2");
        s.base_dir = Some(dir.clone());
        let p = Plan::new(s).unwrap();
        assert_eq!(p.trials.len(), 1);
        assert!(p.skipped[0].contains("none.tif"), "{:?}", p.skipped);
        let mut s = spec("trials = 0\n[[dem]]\nmission = \"m.toml\"");
        s.base_dir = Some(dir.clone());
        let e = Plan::new(s).unwrap_err().to_string();
        assert!(e.contains("`dem`") && e.contains("no trial left") && e.contains("none.tif"), "{e}");
        let mut s = spec("[[dem]]\nmission = \"absent.toml\"");
        s.base_dir = Some(dir);
        let e = Plan::new(s).unwrap_err().to_string();
        assert!(e.contains("dem[0].mission") && e.contains("absent.toml"), "{e}");
    }

    #[test]
    fn shards_are_disjoint_and_cover_every_job() {
        for count in 1..6 {
            let shards: Vec<Shard> = (1..=count).map(|i| Shard::new(i, count, "t").unwrap()).collect();
            for job in 0..50 {
                assert_eq!(shards.iter().filter(|s| s.contains(job)).count(), 1);
            }
        }
    }

    #[test]
    fn shard_text_is_checked() {
        assert_eq!(Shard::parse("2/4").unwrap(), Shard { index: 2, count: 4 });
        for bad in ["0/4", "5/4", "x", "1/0", "2/", "-1/4"] {
            let e = Shard::parse(bad).unwrap_err().to_string();
            assert!(e.starts_with("--shard:"), "{bad}: {e}");
        }
    }

    #[test]
    fn job_array_environments_give_the_slice() {
        let env = |pairs: &[(&str, &str)]| {
            let m: HashMap<String, String> =
                pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
            move |k: &str| m.get(k).cloned()
        };
        assert_eq!(Shard::from_env(env(&[]), None).unwrap(), None);
        let slurm = env(&[("SLURM_ARRAY_TASK_ID", "3"), ("SLURM_ARRAY_TASK_COUNT", "4")]);
        assert_eq!(Shard::from_env(slurm, None).unwrap(), Some(Shard { index: 4, count: 4 }));
        let one_based = env(&[
            ("SLURM_ARRAY_TASK_ID", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
        ]);
        assert_eq!(Shard::from_env(one_based, None).unwrap(), Some(Shard { index: 1, count: 4 }));
        let stepped = env(&[
            ("SLURM_ARRAY_TASK_ID", "8"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("SLURM_ARRAY_TASK_STEP", "4"),
        ]);
        assert_eq!(Shard::from_env(stepped, None).unwrap(), Some(Shard { index: 3, count: 4 }));
        let k8s = env(&[("JOB_COMPLETION_INDEX", "0")]);
        assert_eq!(Shard::from_env(&k8s, Some(3)).unwrap(), Some(Shard { index: 1, count: 3 }));
        let e = Shard::from_env(&k8s, None).unwrap_err().to_string();
        assert!(e.contains("JOB_COMPLETION_INDEX") && e.contains("ROVERNAV_SHARD_COUNT"), "{e}");
        let e = Shard::from_env(env(&[("JOB_COMPLETION_INDEX", "5")]), Some(3)).unwrap_err().to_string();
        assert!(e.contains("6/3"), "{e}");
        let e = Shard::from_env(env(&[("SLURM_ARRAY_TASK_ID", "x")]), None).unwrap_err().to_string();
        assert!(e.starts_with("SLURM_ARRAY_TASK_ID"), "{e}");
    }
}
