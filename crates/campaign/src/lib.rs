//! Campaigns: every navigator on the same generated terrains, Monte Carlo, with a results table
//! and plots (issue 9).
//!
//! A campaign file ([`spec`]) says how many procedural Mars yards to make and how their rock
//! abundance, slope and relief vary, which real-DEM missions to add, and which navigators to
//! run. [`plan`] turns it into trials, each with its own terrain seed drawn from the campaign
//! seed (or given by the file), and a flat list of (trial, navigator) jobs that `--shard i/n`
//! slices for job arrays.
//! [`runner`] runs the jobs in parallel, [`row`] keeps one row per run, [`summary`] reduces
//! the rows per navigator (success with a Wilson interval, path ratio, sensing per metre,
//! compute per cycle), [`plots`] draws SVG charts, [`output`] writes and merges output
//! folders and [`compare`] sets two folders' runs side by side, terrain by terrain. Rows are always sorted by (trial, navigator) before summarising, so a merge of
//! shards gives the same summary as one unsharded run.

pub mod compare;
pub mod output;
pub mod plan;
pub mod plots;
pub mod row;
pub mod runner;
pub mod spec;
pub mod summary;

pub use compare::{Comparison, compare};
pub use output::{CampaignMeta, RowLog, merge_dirs, read_dir, write_dir};
pub use plan::{Job, Plan, Shard, TerrainKind, TrialInfo};
pub use row::Row;
pub use runner::run_jobs;
pub use spec::{CampaignSpec, DemEntry, Draw, YardSpec};
pub use summary::{MachineSummary, NavigatorSummary, Summary, summarise};

/// Why a campaign could not be read, run or merged.
#[derive(Debug, thiserror::Error)]
pub enum CampaignError {
    /// A file could not be read or written.
    #[error("{path}: {message}")]
    Io {
        /// File.
        path: String,
        /// Cause.
        message: String,
    },
    /// TOML or JSON syntax or schema error (the message carries line and field).
    #[error("{path}: {message}")]
    Parse {
        /// File.
        path: String,
        /// What the parser said, flattened to one line.
        message: String,
    },
    /// A field has an invalid value.
    #[error("{path}: field `{field}`: {message}")]
    Invalid {
        /// File (or command-line option).
        path: String,
        /// Dotted field name.
        field: String,
        /// Why.
        message: String,
    },
    /// A bad shard specification (`--shard`, or the job-array environment).
    #[error("{source_name}: {message}")]
    Shard {
        /// Where the shard came from (`--shard`, an environment variable).
        source_name: String,
        /// Why it is bad.
        message: String,
    },
    /// A run could not start (a mission that cannot be built).
    #[error("trial {trial} ({navigator}): {message}")]
    Run {
        /// Trial index.
        trial: usize,
        /// Navigator name.
        navigator: String,
        /// The executive's error.
        message: String,
    },
    /// Output folders that cannot be merged.
    #[error("merge: {0}")]
    Merge(String),
    /// Runs that cannot be compared.
    #[error("compare: {0}")]
    Compare(String),
}

impl CampaignError {
    /// An I/O error on `path`.
    pub(crate) fn io(path: &std::path::Path, e: impl std::fmt::Display) -> Self {
        CampaignError::Io { path: path.display().to_string(), message: e.to_string() }
    }
}
