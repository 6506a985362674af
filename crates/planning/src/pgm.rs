//! Binary PGM (P5) cost maps, as in `costmaps/` of the shared data: pixel values 1..=254 are
//! the cost per unit length, 255 an obstacle; maxval must be 255. The header may carry `#`
//! comments. Rows are kept in image order: cell (row, col) is image row `row` (row 0 = top) and
//! column `col`, exactly as the data README gives start and goal, so the grid is not flipped to
//! the south-up convention of [`rovernav_core::Grid2`].

use crate::{CostGrid, ParseError};

/// A decoded 8-bit greyscale image.
#[derive(Clone, Debug, PartialEq)]
pub struct Pgm {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Maximum grey value from the header.
    pub maxval: u32,
    /// Row-major pixels, row 0 = top.
    pub pixels: Vec<u8>,
}

/// Reads header tokens while tracking the line number for error messages.
struct Header<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
}

impl Header<'_> {
    fn skip_space_and_comments(&mut self) {
        while self.pos < self.bytes.len() {
            match self.bytes[self.pos] {
                b'#' => {
                    while self.pos < self.bytes.len() && self.bytes[self.pos] != b'\n' {
                        self.pos += 1;
                    }
                }
                b'\n' => {
                    self.line += 1;
                    self.pos += 1;
                }
                b' ' | b'\t' | b'\r' => self.pos += 1,
                _ => break,
            }
        }
    }

    fn number(&mut self, what: &str) -> Result<usize, ParseError> {
        self.skip_space_and_comments();
        let begin = self.pos;
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_digit() {
            self.pos += 1;
        }
        std::str::from_utf8(&self.bytes[begin..self.pos])
            .ok()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| ParseError::at_line(self.line, format!("expected {what}")))
    }
}

/// Parses a binary PGM (P5) image with maxval 255.
pub fn parse_pgm(bytes: &[u8]) -> Result<Pgm, ParseError> {
    if bytes.len() < 2 || &bytes[..2] != b"P5" {
        return Err(ParseError::at_line(1, "expected the binary PGM magic `P5`"));
    }
    let mut h = Header { bytes, pos: 2, line: 1 };
    let width = h.number("the image width")?;
    let height = h.number("the image height")?;
    let maxval = h.number("maxval")?;
    if maxval != 255 {
        return Err(ParseError::at_line(h.line, format!("maxval {maxval} unsupported (cost maps use 255)")));
    }
    // Exactly one whitespace byte separates the header from the pixels.
    if h.pos >= bytes.len() || !bytes[h.pos].is_ascii_whitespace() {
        return Err(ParseError::at_line(h.line, "expected whitespace after maxval"));
    }
    let data = &bytes[h.pos + 1..];
    // The product is checked (it may wrap) against the pixel bytes present before allocating.
    let n =
        rovernav_core::limits::checked_elements(&[width as u64, height as u64], 1, Some(data.len() as u64))
            .map_err(|why| ParseError::whole(format!("pixel data: image {why}")))?;
    Ok(Pgm { width, height, maxval: maxval as u32, pixels: data[..n].to_vec() })
}

impl Pgm {
    /// The cost grid: pixel 1..=254 -> that cost, 255 -> obstacle, 0 is an error.
    pub fn cost_grid(&self) -> Result<CostGrid, ParseError> {
        if let Some(i) = self.pixels.iter().position(|&p| p == 0) {
            return Err(ParseError::whole(format!(
                "pixel (row {}, col {}) is 0; cost maps use 1..=254 and 255 for obstacles",
                i / self.width,
                i % self.width
            )));
        }
        let cost = self.pixels.iter().map(|&p| if p == 255 { f32::INFINITY } else { p as f32 }).collect();
        CostGrid::from_costs(self.height, self.width, cost).map_err(|e| ParseError::whole(e.to_string()))
    }
}

/// Parses a P5 cost map straight into a cost grid.
pub fn parse_cost_map(bytes: &[u8]) -> Result<CostGrid, ParseError> {
    parse_pgm(bytes)?.cost_grid()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Cell;

    #[test]
    fn a_pgm_whose_size_wraps_is_refused() {
        let mut bytes = b"P5\n4294967296 4294967296\n255\n".to_vec();
        bytes.extend_from_slice(&[1; 16]);
        let e = parse_pgm(&bytes).unwrap_err().to_string();
        assert!(e.contains("overflows"), "{e}");
        let mut bytes = b"P5\n100000 100000\n255\n".to_vec();
        bytes.extend_from_slice(&[1; 16]);
        let e = parse_pgm(&bytes).unwrap_err().to_string();
        assert!(e.contains("input holds 16"), "{e}");
    }

    #[test]
    fn parses_header_with_comments() {
        let mut bytes = b"P5\n# a comment\n3 2 # trailing\n255\n".to_vec();
        bytes.extend_from_slice(&[1, 2, 255, 4, 5, 6]);
        let g = parse_cost_map(&bytes).unwrap();
        assert_eq!((g.rows(), g.cols()), (2, 3));
        assert_eq!(g.cost(Cell::new(0, 1)), 2.0);
        assert!(g.is_blocked(Cell::new(0, 2)));
        assert_eq!(g.cost(Cell::new(1, 0)), 4.0);
    }

    #[test]
    fn reports_bad_headers_and_short_data() {
        assert_eq!(parse_pgm(b"P2\n1 1\n255\n0").unwrap_err().line, Some(1));
        let e = parse_pgm(b"P5\n# c\n3 x\n255\n").unwrap_err();
        assert_eq!(e.line, Some(3));
        assert!(parse_pgm(b"P5\n2 2\n65535\n").is_err());
        let e = parse_pgm(b"P5\n2 2\n255\n\x01\x01").unwrap_err();
        assert!(e.message.contains("2 x 2 needs 4 bytes but the input holds 2"), "{}", e.message);
        assert!(parse_cost_map(b"P5\n1 1\n255\n\x00").is_err());
    }
}
