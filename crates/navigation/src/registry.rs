//! The registry: one table of navigators and one of localisers, each entry a name, a
//! constructor, a parameter schema and a one-line doc (as Nav2 keeps its plugins by name).
//!
//! A navigator is one module exporting an `ENTRY` and one line in [`BUILTIN_NAVIGATORS`].
//! Combinations are options, not names: a navigator entry lists the global planners it can
//! run under ([`Variant`]), each with the short label reports and campaigns know it by
//! (`astar-grid` is `grid` under `astar`, `mrpta` is `grid` under `dstar-lite`,
//! `gestalt+field-dstar` is `gestalt` under `field-dstar`), and a mission chooses with
//! `global_planner`. A localiser takes `[localizer_params]`; `ekf-ml-targets` is an alias of
//! `ekf-ml` with `select_targets = 1`. The look-back decorator is the registry's concern: a
//! localiser entry that matches terrain asks for it, and the navigator is wrapped
//! ([`Registry::decorated`]); the old `+look-back` suffix still names it.
//!
//! The registry is extendable at run time: a program installs
//! `Registry::builtin().with(MY_ENTRY)` once with [`install`] before the first run, and every
//! entry point (runs, campaigns, later legs' fresh navigators) builds from [`registry`].

use crate::look_back::{LOOK_BACK_SUFFIX, LookBack};
use crate::params::{NavigatorError, NavigatorParams, Param, configured, value};
use rovernav_core::{Grid2, Localizer, Navigator, Pose3, RoverConfig};
use std::sync::OnceLock;

/// One parameter an entry takes in a mission's `[navigator_params]` or `[localizer_params]`.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamInfo {
    /// Name in the mission file.
    pub name: &'static str,
    /// Unit and valid range.
    pub unit: &'static str,
    /// One-line meaning.
    pub doc: &'static str,
    /// The value used when the mission does not set it (in the parameter's unit).
    pub default: f64,
}

/// The listing of a parameter table, with the defaults read from `defaults`.
pub fn param_info<C>(mut defaults: C, table: Vec<Param<C>>) -> Vec<ParamInfo> {
    table
        .iter()
        .map(|p| ParamInfo {
            name: p.name,
            unit: p.unit.label(),
            doc: p.doc,
            default: to_twelve_digits(value(&mut defaults, p)),
        })
        .collect()
}

/// `x` rounded to twelve significant digits: a default stored in radians and listed in degrees
/// reads 30, not 29.999999999999996.
fn to_twelve_digits(x: f64) -> f64 {
    if !x.is_finite() || x == 0.0 {
        return x;
    }
    format!("{x:.11e}").parse().unwrap_or(x)
}

/// A global planner a navigator can run under, and the label of that combination.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Variant {
    /// The mission file's `global_planner` value.
    pub global_planner: &'static str,
    /// The combination's name in reports, campaigns and old mission files.
    pub label: &'static str,
}

/// What a navigator constructor gets.
pub struct NavigatorBuild<'a> {
    /// The combination's label (the navigator reports it as its name).
    pub label: &'static str,
    /// The chosen global planner (`None` for a navigator without a choice).
    pub global_planner: Option<&'static str>,
    /// The rover.
    pub rover: &'a RoverConfig,
    /// The mission's `[navigator_params]`.
    pub params: &'a NavigatorParams,
}

impl NavigatorBuild<'_> {
    /// `defaults` with the mission's parameters applied from `table` (errors name the label).
    pub fn configured<C: Clone>(&self, defaults: C, table: &[Param<C>]) -> Result<C, NavigatorError> {
        configured(self.label, defaults, table, self.params)
    }
}

/// One navigator of the registry.
#[derive(Clone, Copy, Debug)]
pub struct NavigatorEntry {
    /// Registry name.
    pub name: &'static str,
    /// One-line description.
    pub doc: &'static str,
    /// The global planners it can run under, the default first; empty for none.
    pub global_planners: &'static [Variant],
    /// Its parameters with their defaults.
    pub params: fn() -> Vec<ParamInfo>,
    /// Its constructor.
    pub build: fn(&NavigatorBuild<'_>) -> Result<Box<dyn Navigator>, NavigatorError>,
}

impl NavigatorEntry {
    /// Every label of the entry, in table order (its name when it has no planner choice).
    pub fn labels(&self) -> Vec<&'static str> {
        match self.global_planners {
            [] => vec![self.name],
            variants => variants.iter().map(|v| v.label).collect(),
        }
    }
}

/// What a localiser constructor gets.
pub struct LocalizerBuild<'a> {
    /// Registry name (errors name it).
    pub name: &'static str,
    /// The rover.
    pub rover: &'a RoverConfig,
    /// The pose the localiser starts from.
    pub initial: Pose3,
    /// The mission's `[localizer_params]` (an alias's included).
    pub params: &'a NavigatorParams,
    /// The terrain's orbital map given before the traverse (world frame, heights in metres,
    /// NaN unknown), for localisers that match against one; `None` when the run has none.
    pub prior_map: Option<&'a Grid2<f32>>,
}

impl LocalizerBuild<'_> {
    /// `defaults` with the mission's parameters applied from `table` (errors name the localiser).
    pub fn configured<C: Clone>(&self, defaults: C, table: &[Param<C>]) -> Result<C, NavigatorError> {
        configured(self.name, defaults, table, self.params).map_err(NavigatorError::of_localizer)
    }
}

/// One localiser of the registry.
#[derive(Clone, Copy, Debug)]
pub struct LocalizerEntry {
    /// Registry name.
    pub name: &'static str,
    /// One-line description.
    pub doc: &'static str,
    /// Whether it corrects its pose by terrain-map matching (so the navigator looks back).
    pub matches_terrain: bool,
    /// Whether it needs the terrain's orbital map ([`LocalizerBuild::prior_map`]).
    pub needs_prior_map: bool,
    /// Its parameters with their defaults.
    pub params: fn() -> Vec<ParamInfo>,
    /// Its constructor.
    pub build: fn(&LocalizerBuild<'_>) -> Result<Box<dyn Localizer>, NavigatorError>,
}

/// An old localiser name standing for a localiser with some parameters set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalizerAlias {
    /// The old name.
    pub name: &'static str,
    /// The localiser it stands for.
    pub localizer: &'static str,
    /// The parameters it sets.
    pub params: &'static [(&'static str, f64)],
}

/// The built-in navigators.
pub const BUILTIN_NAVIGATORS: &[NavigatorEntry] = &[
    crate::grid_nav::ENTRY,
    crate::gestalt::ENTRY,
    crate::sr2::ENTRY,
    crate::nat::ENTRY,
    crate::roverbug::ENTRY,
];

/// A navigator chosen by name and options.
#[derive(Clone, Copy, Debug)]
pub struct NavigatorChoice {
    /// The registry entry.
    pub entry: NavigatorEntry,
    /// The global planner (`None` for a navigator without a choice).
    pub global_planner: Option<&'static str>,
    /// The combination's label.
    pub label: &'static str,
    /// Wrapped in the look-back decorator.
    pub look_back: bool,
}

impl NavigatorChoice {
    /// The one-string name of the choice: its label, with `+look-back` when decorated.
    pub fn spec(&self) -> String {
        format!("{}{}", self.label, if self.look_back { LOOK_BACK_SUFFIX } else { "" })
    }
}

/// A localiser chosen by name and parameters.
#[derive(Clone, Debug)]
pub struct LocalizerChoice {
    /// The registry entry.
    pub entry: LocalizerEntry,
    /// Its parameters (an alias's and the mission's).
    pub params: NavigatorParams,
}

/// The navigator and localiser tables.
#[derive(Clone, Debug)]
pub struct Registry {
    navigators: Vec<NavigatorEntry>,
    localizers: Vec<LocalizerEntry>,
    localizer_aliases: Vec<LocalizerAlias>,
}

static INSTALLED: OnceLock<Registry> = OnceLock::new();

/// The registry every run builds from: the installed one, else the built-in one.
pub fn registry() -> &'static Registry {
    INSTALLED.get_or_init(Registry::builtin)
}

/// Makes `registry` the one every run builds from; refused (giving it back) once a registry
/// is in use, so that one process never builds the same name two ways.
pub fn install(registry: Registry) -> Result<(), Box<Registry>> {
    INSTALLED.set(registry).map_err(Box::new)
}

impl Registry {
    /// The built-in navigators and localisers.
    pub fn builtin() -> Self {
        Self {
            navigators: BUILTIN_NAVIGATORS.to_vec(),
            localizers: crate::localizers::BUILTIN_LOCALIZERS.to_vec(),
            localizer_aliases: crate::localizers::LOCALIZER_ALIASES.to_vec(),
        }
    }

    /// This registry with one more navigator. A name or label already taken is a programming
    /// error and panics, naming it.
    pub fn with(mut self, entry: NavigatorEntry) -> Self {
        let taken = self.navigator_names();
        for name in std::iter::once(entry.name).chain(entry.labels()) {
            assert!(!taken.contains(&name), "navigator name `{name}` is registered twice");
        }
        self.navigators.push(entry);
        self
    }

    /// This registry with one more localiser (a name already taken panics, naming it).
    pub fn with_localizer(mut self, entry: LocalizerEntry) -> Self {
        assert!(
            !self.localizer_names().contains(&entry.name),
            "localizer name `{}` is registered twice",
            entry.name
        );
        self.localizers.push(entry);
        self
    }

    /// The navigator entries in table order.
    pub fn navigators(&self) -> &[NavigatorEntry] {
        &self.navigators
    }

    /// The localiser entries in table order.
    pub fn localizers(&self) -> &[LocalizerEntry] {
        &self.localizers
    }

    /// The old localiser names and what they stand for.
    pub fn localizer_aliases(&self) -> &[LocalizerAlias] {
        &self.localizer_aliases
    }

    /// Every navigator combination's label in table order (what a campaign's `all` runs).
    pub fn navigator_names(&self) -> Vec<&'static str> {
        self.navigators.iter().flat_map(NavigatorEntry::labels).collect()
    }

    /// Every name a mission may give as `navigator`: entries, then labels not already listed.
    pub fn navigator_names_and_entries(&self) -> Vec<&'static str> {
        let mut names: Vec<&'static str> = self.navigators.iter().map(|e| e.name).collect();
        for label in self.navigator_names() {
            if !names.contains(&label) {
                names.push(label);
            }
        }
        names
    }

    /// The localiser names, then the aliases.
    pub fn localizer_names(&self) -> Vec<&'static str> {
        let entries = self.localizers.iter().map(|e| e.name);
        entries.chain(self.localizer_aliases.iter().map(|a| a.name)).collect()
    }

    /// The navigator `name` (an entry, a label such as `mrpta`, `entry+planner`, any of them
    /// with `+look-back`) under `global_planner` when given.
    pub fn navigator(
        &self,
        name: &str,
        global_planner: Option<&str>,
    ) -> Result<NavigatorChoice, NavigatorError> {
        let (base, look_back) = match name.strip_suffix(LOOK_BACK_SUFFIX) {
            Some(base) => (base, true),
            None => (name, false),
        };
        let choice = |entry: NavigatorEntry, variant: Option<Variant>| NavigatorChoice {
            entry,
            global_planner: variant.map(|v| v.global_planner),
            label: variant.map_or(entry.name, |v| v.label),
            look_back,
        };
        let unknown_planner = |entry: &NavigatorEntry, planner: &str| NavigatorError::UnknownGlobalPlanner {
            navigator: entry.name.to_string(),
            planner: planner.to_string(),
            known: entry.global_planners.iter().map(|v| v.global_planner).collect(),
        };
        for entry in &self.navigators {
            if entry.name == base {
                let variant = match (global_planner, entry.global_planners) {
                    (None, []) => None,
                    (None, variants) => Some(variants[0]),
                    (Some(p), variants) => Some(
                        *variants
                            .iter()
                            .find(|v| v.global_planner == p)
                            .ok_or_else(|| unknown_planner(entry, p))?,
                    ),
                };
                return Ok(choice(*entry, variant));
            }
            for v in entry.global_planners {
                let spelled = base.strip_prefix(entry.name).and_then(|r| r.strip_prefix('+'));
                if v.label == base || spelled == Some(v.global_planner) {
                    if let Some(p) = global_planner.filter(|p| *p != v.global_planner) {
                        return Err(NavigatorError::ConflictingGlobalPlanner {
                            navigator: base.to_string(),
                            planner: p.to_string(),
                            implied: v.global_planner,
                        });
                    }
                    return Ok(choice(*entry, Some(*v)));
                }
            }
        }
        Err(NavigatorError::UnknownNavigator {
            name: name.to_string(),
            known: self.navigator_names_and_entries(),
        })
    }

    /// A fresh navigator by name (see [`Registry::navigator`]) with the mission's parameters.
    pub fn build_navigator(
        &self,
        name: &str,
        rover: &RoverConfig,
        params: &NavigatorParams,
    ) -> Result<Box<dyn Navigator>, NavigatorError> {
        let choice = self.navigator(name, None)?;
        let build =
            NavigatorBuild { label: choice.label, global_planner: choice.global_planner, rover, params };
        let navigator = (choice.entry.build)(&build)?;
        Ok(if choice.look_back { Box::new(LookBack::new(navigator, Default::default())) } else { navigator })
    }

    /// Checks a navigator's name and parameters without keeping the navigator.
    pub fn check_navigator(&self, name: &str, params: &NavigatorParams) -> Result<(), NavigatorError> {
        self.build_navigator(name, &RoverConfig::default(), params).map(drop)
    }

    /// The navigator name a run builds every leg from: `name`, wrapped in the look-back
    /// decorator when `localizer` matches terrain (and needs views back over the terrain
    /// crossed). Unknown names come back as given, for the run to report.
    pub fn decorated(&self, name: &str, localizer: &str) -> String {
        match (self.navigator(name, None), self.localizer(localizer, &NavigatorParams::new())) {
            (Ok(mut choice), Ok(loc)) => {
                choice.look_back |= loc.entry.matches_terrain;
                choice.spec()
            }
            _ => name.to_string(),
        }
    }

    /// The localiser `name` (an entry, an alias, or `entry(k=v,...)`) with `params` over the
    /// name's own.
    pub fn localizer(&self, name: &str, params: &NavigatorParams) -> Result<LocalizerChoice, NavigatorError> {
        let unknown =
            || NavigatorError::UnknownLocalizer { name: name.to_string(), known: self.localizer_names() };
        let (base, mut merged) = parse_localizer_spec(name).ok_or_else(unknown)?;
        let base = match self.localizer_aliases.iter().find(|a| a.name == base) {
            Some(alias) => {
                for (k, v) in alias.params {
                    merged.entry(k.to_string()).or_insert(*v);
                }
                alias.localizer
            }
            None => base,
        };
        let entry = *self.localizers.iter().find(|e| e.name == base).ok_or_else(unknown)?;
        merged.extend(params.iter().map(|(k, v)| (k.clone(), *v)));
        Ok(LocalizerChoice { entry, params: merged })
    }

    /// The one-string name of a localiser choice: an alias that stands for exactly it, else
    /// the entry's name, with `(k=v,...)` for parameters set.
    pub fn localizer_spec(&self, choice: &LocalizerChoice) -> String {
        let alias = self.localizer_aliases.iter().find(|a| {
            a.localizer == choice.entry.name
                && a.params.len() == choice.params.len()
                && a.params.iter().all(|(k, v)| choice.params.get(*k) == Some(v))
        });
        match alias {
            Some(a) => a.name.to_string(),
            None if choice.params.is_empty() => choice.entry.name.to_string(),
            None => {
                let pairs: Vec<String> = choice.params.iter().map(|(k, v)| format!("{k}={v}")).collect();
                format!("{}({})", choice.entry.name, pairs.join(","))
            }
        }
    }

    /// A localiser by name (see [`Registry::localizer`]) starting at `initial`, without a prior
    /// map.
    pub fn build_localizer(
        &self,
        name: &str,
        rover: &RoverConfig,
        initial: Pose3,
        params: &NavigatorParams,
    ) -> Result<Box<dyn Localizer>, NavigatorError> {
        self.build_localizer_with_prior(name, rover, initial, params, None)
    }

    /// Whether the localiser `name` needs an orbital map (false for an unknown name).
    pub fn localizer_needs_prior_map(&self, name: &str) -> bool {
        self.localizer(name, &NavigatorParams::new()).is_ok_and(|c| c.entry.needs_prior_map)
    }

    /// [`Registry::build_localizer`] with the terrain's orbital map when the run has one.
    pub fn build_localizer_with_prior(
        &self,
        name: &str,
        rover: &RoverConfig,
        initial: Pose3,
        params: &NavigatorParams,
        prior_map: Option<&Grid2<f32>>,
    ) -> Result<Box<dyn Localizer>, NavigatorError> {
        let choice = self.localizer(name, params)?;
        let known: Vec<&'static str> = (choice.entry.params)().iter().map(|p| p.name).collect();
        if let Some(param) = choice.params.keys().find(|k| !known.contains(&k.as_str())) {
            let navigator = choice.entry.name.to_string();
            return Err(NavigatorError::UnknownParam {
                kind: "localizer",
                navigator,
                param: param.clone(),
                known,
            });
        }
        if choice.entry.needs_prior_map && prior_map.is_none() {
            return Err(NavigatorError::MissingPriorMap { localizer: choice.entry.name.to_string() });
        }
        let build =
            LocalizerBuild { name: choice.entry.name, rover, initial, params: &choice.params, prior_map };
        (choice.entry.build)(&build)
    }

    /// Checks a localiser's name and parameters without keeping the localiser (one that needs
    /// an orbital map is built on a small flat stand-in: the run gives the real one).
    pub fn check_localizer(&self, name: &str, params: &NavigatorParams) -> Result<(), NavigatorError> {
        let geometry =
            rovernav_core::GridGeometry { cols: 4, rows: 4, resolution: 1.0, origin_x: -2.0, origin_y: -2.0 };
        let stand_in = Grid2::filled(geometry, 0.0f32);
        let initial = Pose3::default();
        self.build_localizer_with_prior(name, &RoverConfig::default(), initial, params, Some(&stand_in))
            .map(drop)
    }
}

/// `name` or `name(k=v,k=v)` as the name and its parameters; `None` if malformed.
fn parse_localizer_spec(spec: &str) -> Option<(&str, NavigatorParams)> {
    let Some((name, rest)) = spec.split_once('(') else { return Some((spec, NavigatorParams::new())) };
    let inner = rest.strip_suffix(')')?;
    let mut params = NavigatorParams::new();
    for pair in inner.split(',').filter(|p| !p.is_empty()) {
        let (k, v) = pair.split_once('=')?;
        params.insert(k.trim().to_string(), v.trim().parse().ok()?);
    }
    Some((name, params))
}

#[cfg(test)]
#[path = "registry_tests.rs"]
mod tests;
