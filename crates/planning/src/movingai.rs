//! Parsers for the MovingAI grid pathfinding benchmark (N. Sturtevant, "Benchmarks for
//! Grid-Based Pathfinding", IEEE TCIAIG 4(2), 2012): `.map` files and `.scen` scenario lists.
//!
//! Terrain letters: `.` and `G` are free; `@`, `O` and `T` (trees) are blocked, as the benchmark's
//! published optimal lengths assume; `S` (swamp) and `W` (water) are also treated as blocked for
//! simplicity (the benchmark maps used here contain neither as passable terrain).
//! Map row 0 is the first map line (the top) and scenario coordinates are (x = column,
//! y = row); cells are (row, col) = (y, x). Line endings may be LF or CRLF.

use crate::{Cell, CostGrid, ParseError};

/// A MovingAI map: blocked flags, row-major, row 0 = first map line.
#[derive(Clone, Debug, PartialEq)]
pub struct MovingAiMap {
    /// Rows.
    pub height: usize,
    /// Columns.
    pub width: usize,
    /// Row-major blocked flags.
    pub blocked: Vec<bool>,
}

impl MovingAiMap {
    /// Whether a cell is blocked (cells outside the map count as blocked).
    pub fn is_blocked(&self, cell: Cell) -> bool {
        cell.row >= self.height || cell.col >= self.width || self.blocked[cell.row * self.width + cell.col]
    }
    /// The cost grid: free cells cost 1, blocked ones are obstacles.
    pub fn cost_grid(&self) -> CostGrid {
        CostGrid::from_blocked(self.height, self.width, &self.blocked)
            .expect("blocked flags have height x width entries")
    }
}

/// One scenario line.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    /// Difficulty bucket.
    pub bucket: u32,
    /// The map named in the scenario (may include folders).
    pub map: String,
    /// Map width given in the scenario.
    pub map_width: usize,
    /// Map height given in the scenario.
    pub map_height: usize,
    /// Start cell.
    pub start: Cell,
    /// Goal cell.
    pub goal: Cell,
    /// Published optimal octile length.
    pub optimal: f64,
    /// 1-based line in the `.scen` file.
    pub line: usize,
}

fn free_letter(ch: u8) -> Option<bool> {
    match ch {
        b'.' | b'G' => Some(false),
        b'@' | b'O' | b'T' | b'S' | b'W' => Some(true),
        _ => None,
    }
}

/// Parses a `.map` file.
pub fn parse_map(text: &str) -> Result<MovingAiMap, ParseError> {
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim_end()));
    let mut height = None;
    let mut width = None;
    let mut saw_type = false;
    let mut map_line = 0;
    for (n, line) in lines.by_ref() {
        let mut words = line.split_whitespace();
        match (words.next(), words.next()) {
            (None, _) => continue,
            (Some("type"), Some(_)) => saw_type = true,
            (Some("height"), Some(v)) => {
                height = Some(
                    v.parse::<usize>()
                        .map_err(|_| ParseError::at_line(n, format!("expected `height N`, got `{line}`")))?,
                )
            }
            (Some("width"), Some(v)) => {
                width = Some(
                    v.parse::<usize>()
                        .map_err(|_| ParseError::at_line(n, format!("expected `width N`, got `{line}`")))?,
                )
            }
            (Some("map"), None) => {
                map_line = n;
                break;
            }
            _ if !saw_type => {
                return Err(ParseError::at_line(n, "expected `type octile`"));
            }
            _ if height.is_none() => {
                return Err(ParseError::at_line(n, "expected `height N`"));
            }
            _ if width.is_none() => {
                return Err(ParseError::at_line(n, "expected `width N`"));
            }
            _ => return Err(ParseError::at_line(n, "expected `map`")),
        }
    }
    if map_line == 0 {
        return Err(ParseError::whole("missing `map` line"));
    }
    let height = height.ok_or_else(|| ParseError::at_line(map_line, "`map` before `height N`"))?;
    let width = width.ok_or_else(|| ParseError::at_line(map_line, "`map` before `width N`"))?;
    // Each cell is one character of the text: a header promising more cells than the text holds
    // is refused before allocating.
    let cells =
        rovernav_core::limits::checked_elements(&[height as u64, width as u64], 1, Some(text.len() as u64))
            .map_err(|why| ParseError::at_line(map_line, format!("map {why}")))?;
    let mut blocked = Vec::with_capacity(cells);
    let mut rows = 0;
    for (n, line) in lines {
        if rows == height {
            if line.is_empty() {
                continue;
            }
            return Err(ParseError::at_line(n, format!("more than {height} map rows")));
        }
        if line.len() != width {
            return Err(ParseError::at_line(
                n,
                format!("map row has {} characters, expected {width}", line.len()),
            ));
        }
        for (col, ch) in line.bytes().enumerate() {
            let b = free_letter(ch).ok_or_else(|| {
                ParseError::at_line(n, format!("unknown terrain `{}` at column {col}", ch as char))
            })?;
            blocked.push(b);
        }
        rows += 1;
    }
    if rows != height {
        return Err(ParseError::whole(format!("map has {rows} rows, header says {height}")));
    }
    Ok(MovingAiMap { height, width, blocked })
}

/// Parses a `.scen` file (an optional `version` line, then one scenario per line; buckets may be
/// unsorted).
pub fn parse_scenarios(text: &str) -> Result<Vec<Scenario>, ParseError> {
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let n = i + 1;
        let line = raw.trim();
        if line.is_empty() || (out.is_empty() && line.starts_with("version")) {
            continue;
        }
        let fields: Vec<&str> = if line.contains('\t') {
            line.split('\t').map(str::trim).collect()
        } else {
            line.split_whitespace().collect()
        };
        if fields.len() != 9 {
            return Err(ParseError::at_line(
                n,
                format!(
                    "expected 9 fields (bucket map width height sx sy gx gy optimal), got {}",
                    fields.len()
                ),
            ));
        }
        let int = |k: usize, name: &str| {
            fields[k].parse::<usize>().map_err(|_| {
                ParseError::at_line(n, format!("field {name}: expected an integer, got `{}`", fields[k]))
            })
        };
        let optimal =
            fields[8].parse::<f64>().ok().filter(|v| v.is_finite() && *v >= 0.0).ok_or_else(|| {
                ParseError::at_line(
                    n,
                    format!("field optimal: expected a finite length >= 0, got `{}`", fields[8]),
                )
            })?;
        out.push(Scenario {
            bucket: int(0, "bucket")? as u32,
            map: fields[1].to_string(),
            map_width: int(2, "width")?,
            map_height: int(3, "height")?,
            start: Cell::new(int(5, "start y")?, int(4, "start x")?),
            goal: Cell::new(int(7, "goal y")?, int(6, "goal x")?),
            optimal,
            line: n,
        });
    }
    if out.is_empty() {
        return Err(ParseError::whole("no scenario (an empty `.scen` file)"));
    }
    Ok(out)
}

/// Checks that scenarios fit the map they are run on, naming the first offending line.
pub fn check_scenarios(map: &MovingAiMap, scenarios: &[Scenario]) -> Result<(), ParseError> {
    for s in scenarios {
        if s.map_width != map.width || s.map_height != map.height {
            return Err(ParseError::at_line(
                s.line,
                format!(
                    "scenario is for a {}x{} map, the map is {}x{}",
                    s.map_width, s.map_height, map.width, map.height
                ),
            ));
        }
        for (what, c) in [("start", s.start), ("goal", s.goal)] {
            if c.row >= map.height || c.col >= map.width {
                return Err(ParseError::at_line(s.line, format!("{what} outside the map")));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_map_header_larger_than_its_file_is_refused_before_allocating() {
        let e = parse_map("type octile\nheight 1000000\nwidth 1000000\nmap\n..\n").unwrap_err();
        assert!(e.to_string().contains("line 4") && e.to_string().contains("input holds"), "{e}");
    }

    #[test]
    fn an_empty_scenario_file_is_refused() {
        let e = parse_scenarios("version 1\n").unwrap_err();
        assert!(e.to_string().contains("no scenario"), "{e}");
    }

    #[test]
    fn a_nan_or_negative_optimum_is_refused() {
        for bad in ["nan", "inf", "-1"] {
            let text = format!("version 1\n0\ta.map\t3\t2\t0\t0\t1\t0\t{bad}\n");
            let e = parse_scenarios(&text).unwrap_err();
            assert!(e.to_string().contains("line 2") && e.to_string().contains("optimal"), "{bad}: {e}");
        }
    }

    #[test]
    fn parses_a_small_map_with_crlf() {
        let text = "type octile\r\nheight 2\r\nwidth 3\r\nmap\r\n.@T\r\nG.S\r\n";
        let m = parse_map(text).unwrap();
        assert_eq!((m.height, m.width), (2, 3));
        assert_eq!(m.blocked, vec![false, true, true, false, false, true]);
    }

    #[test]
    fn reports_the_line_of_a_bad_header() {
        let e = parse_map("type octile\nheigth 2\nwidth 3\nmap\n...\n...\n").unwrap_err();
        assert_eq!(e.line, Some(2));
        assert_eq!(e.in_file("maze.map").to_string(), "maze.map line 2: expected `height N`");
        let e = parse_map("type octile\nheight 2\nwidth 3\nmap\n...\n..x\n").unwrap_err();
        assert_eq!(e.line, Some(6));
        let e = parse_map("type octile\nheight 3\nwidth 3\nmap\n...\n...\n").unwrap_err();
        assert!(e.message.contains("2 rows"));
    }

    #[test]
    fn parses_scenarios_with_and_without_folders() {
        let text = "version 1\r\n3\tmaps/dao/arena.map\t49\t49\t1\t11\t1\t12\t1\r\n0\tarena.map\t49\t49\t5\t6\t7\t8\t2.82842712\r\n";
        let s = parse_scenarios(text).unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].bucket, 3);
        assert_eq!(s[0].start, Cell::new(11, 1));
        assert_eq!(s[1].goal, Cell::new(8, 7));
        assert_eq!(s[1].line, 3);
        let e = parse_scenarios("version 1\n0\ta.map\t1\t1\t0\t0\n").unwrap_err();
        assert_eq!(e.line, Some(2));
    }
}
