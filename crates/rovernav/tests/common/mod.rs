//! Fixtures shared by the command-line tests.

/// A small procedural yard (12 m, seed 3) whose traverse takes a few seconds in debug.
pub const SMALL_YARD: &str = r#"
name = "small-yard"
seed = 3
[terrain]
kind = "procedural"
size_m = 12.0
resolution_m = 0.05
rock_abundance = 0.12
[start]
x = 2.0
y = 2.0
yaw_deg = 10.0
[goal]
x = 9.5
y = 8.5
"#;
