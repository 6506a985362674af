//! PDS3 images: ODL labels (attached at the start of the data file, or detached in a `.lbl`),
//! IMAGE objects of integer or IEEE/PC float samples, global simple-cylindrical DEMs such as
//! the MOLA MEGDR, and the CAHVOR camera model of MSL camera labels.
//!
//! File names in labels are often upper case while the files on disk are lower case, so they
//! are resolved case-insensitively in the label's folder.

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use super::LoadError;
use crate::ops::min_max_ignoring_nan;

/// Most bytes read from the start of a file while looking for its label's `END`.
const MAX_LABEL_BYTES: u64 = 4 << 20;

/// A value in an ODL label.
#[derive(Clone, Debug, PartialEq)]
pub enum Pds3Value {
    /// A double-quoted string (line breaks and indentation folded to single spaces).
    Text(String),
    /// A bare or single-quoted literal: an identifier, a date, a time.
    Symbol(String),
    /// A number (integers, reals and based integers such as `2#0111#`), with its `<UNIT>`.
    Number {
        /// The value.
        value: f64,
        /// The unit in angle brackets, if any, as written.
        unit: Option<String>,
    },
    /// A parenthesised or braced list.
    Sequence(Vec<Pds3Value>),
}

impl Pds3Value {
    /// The number, if this is one.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Pds3Value::Number { value, .. } => Some(*value),
            _ => None,
        }
    }

    /// The text of a string or literal.
    pub fn as_str(&self) -> Option<&str> {
        match self {
            Pds3Value::Text(s) | Pds3Value::Symbol(s) => Some(s),
            _ => None,
        }
    }

    /// The numbers of a list (or of a single number).
    pub fn as_f64_vec(&self) -> Option<Vec<f64>> {
        match self {
            Pds3Value::Sequence(items) => items.iter().map(Pds3Value::as_f64).collect(),
            Pds3Value::Number { value, .. } => Some(vec![*value]),
            _ => None,
        }
    }
}

/// What opened a block of a label.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockKind {
    /// The top level of the label.
    Root,
    /// `OBJECT = NAME`.
    Object,
    /// `GROUP = NAME`.
    Group,
}

/// A level of a label: its keyword/value pairs in order and its nested objects and groups.
#[derive(Clone, Debug, PartialEq)]
pub struct Pds3Block {
    /// Object or group name (empty for the root).
    pub name: String,
    /// How the block was opened.
    pub kind: BlockKind,
    /// Keyword/value pairs, in label order (pointers keep their `^`).
    pub entries: Vec<(String, Pds3Value)>,
    /// Nested blocks, in label order.
    pub children: Vec<Pds3Block>,
}

impl Pds3Block {
    fn new(name: String, kind: BlockKind) -> Self {
        Self { name, kind, entries: Vec::new(), children: Vec::new() }
    }

    /// The value of a keyword at this level (case-insensitive).
    pub fn get(&self, key: &str) -> Option<&Pds3Value> {
        self.entries.iter().find(|(k, _)| k.eq_ignore_ascii_case(key)).map(|(_, v)| v)
    }

    /// A number at this level.
    pub fn get_f64(&self, key: &str) -> Option<f64> {
        self.get(key).and_then(Pds3Value::as_f64)
    }

    /// A string or literal at this level.
    pub fn get_str(&self, key: &str) -> Option<&str> {
        self.get(key).and_then(Pds3Value::as_str)
    }

    /// The first block with this name at any depth below (case-insensitive), depth first.
    pub fn find(&self, name: &str) -> Option<&Pds3Block> {
        for child in &self.children {
            if child.name.eq_ignore_ascii_case(name) {
                return Some(child);
            }
            if let Some(found) = child.find(name) {
                return Some(found);
            }
        }
        None
    }
}

/// A parsed PDS3 label.
#[derive(Clone, Debug, PartialEq)]
pub struct Pds3Label {
    /// The file the label was read from.
    pub file: PathBuf,
    /// The top level.
    pub root: Pds3Block,
    /// Bytes of text up to and including the `END` statement.
    pub length: usize,
}

impl Pds3Label {
    /// Reads the label at the start of a file (attached or detached).
    pub fn open(path: impl AsRef<Path>) -> Result<Self, LoadError> {
        let path = path.as_ref();
        let mut f = File::open(path).map_err(|e| LoadError::io(path, e))?;
        let mut prefix = Vec::new();
        (&mut f).take(MAX_LABEL_BYTES).read_to_end(&mut prefix).map_err(|e| LoadError::io(path, e))?;
        Self::parse(path, &String::from_utf8_lossy(&prefix))
    }

    /// Parses label text; parsing stops at the `END` statement, so binary data may follow.
    pub fn parse(file: &Path, text: &str) -> Result<Self, LoadError> {
        Parser { file, text: text.as_bytes(), pos: 0, line: 1 }.label()
    }

    /// A top-level keyword's value.
    pub fn get(&self, key: &str) -> Option<&Pds3Value> {
        self.root.get(key)
    }

    /// The first object or group of this name.
    pub fn block(&self, name: &str) -> Option<&Pds3Block> {
        self.root.find(name)
    }

    /// Every keyword/value pair with its dotted block path (e.g. `IMAGE.LINES`), in label order.
    pub fn flatten(&self) -> Vec<(String, &Pds3Value)> {
        fn walk<'a>(block: &'a Pds3Block, prefix: &str, out: &mut Vec<(String, &'a Pds3Value)>) {
            for (k, v) in &block.entries {
                out.push((format!("{prefix}{k}"), v));
            }
            for child in &block.children {
                walk(child, &format!("{prefix}{}.", child.name), out);
            }
        }
        let mut out = Vec::new();
        walk(&self.root, "", &mut out);
        out
    }

    /// The CAHVOR (or CAHV) camera model of the `GEOMETRIC_CAMERA_MODEL` group, if present.
    pub fn cahvor(&self) -> Option<CahvorModel> {
        let group = self.block("GEOMETRIC_CAMERA_MODEL")?;
        let component = |i: usize| -> Option<[f64; 3]> {
            let v = group.get(&format!("MODEL_COMPONENT_{i}"))?.as_f64_vec()?;
            (v.len() == 3).then(|| [v[0], v[1], v[2]])
        };
        let (c, a, h, v) = (component(1)?, component(2)?, component(3)?, component(4)?);
        let (o, r) = match (component(5), component(6)) {
            (Some(o), Some(r)) => (o, r),
            _ => (a, [0.0; 3]),
        };
        Some(CahvorModel { c, a, h, v, o, r })
    }
}

struct Parser<'a> {
    file: &'a Path,
    text: &'a [u8],
    pos: usize,
    line: usize,
}

impl Parser<'_> {
    fn error(&self, message: impl Into<String>) -> LoadError {
        LoadError::Syntax { file: self.file.to_path_buf(), line: self.line, message: message.into() }
    }

    fn peek(&self) -> Option<u8> {
        self.text.get(self.pos).copied()
    }

    fn bump(&mut self) -> Option<u8> {
        let c = self.peek()?;
        self.pos += 1;
        if c == b'\n' {
            self.line += 1;
        }
        Some(c)
    }

    /// Skips whitespace and `/* */` comments.
    fn skip_blank(&mut self) -> Result<(), LoadError> {
        loop {
            match self.peek() {
                Some(c) if c.is_ascii_whitespace() || c == 0 => {
                    self.bump();
                }
                Some(b'/') if self.text.get(self.pos + 1) == Some(&b'*') => {
                    let start_line = self.line;
                    self.pos += 2;
                    loop {
                        match self.bump() {
                            Some(b'*') if self.peek() == Some(b'/') => {
                                self.pos += 1;
                                break;
                            }
                            Some(_) => {}
                            None => {
                                self.line = start_line;
                                return Err(self.error("comment never closed"));
                            }
                        }
                    }
                }
                _ => return Ok(()),
            }
        }
    }

    fn keyword(&mut self) -> String {
        let start = self.pos;
        while let Some(c) = self.peek() {
            if c.is_ascii_alphanumeric() || matches!(c, b'_' | b'^' | b':') {
                self.pos += 1;
            } else {
                break;
            }
        }
        String::from_utf8_lossy(&self.text[start..self.pos]).into_owned()
    }

    fn label(mut self) -> Result<Pds3Label, LoadError> {
        let mut stack = vec![Pds3Block::new(String::new(), BlockKind::Root)];
        loop {
            self.skip_blank()?;
            if self.peek().is_none() {
                return Err(self.error("label has no END statement"));
            }
            let key = self.keyword();
            if key.is_empty() {
                let c = self.peek().unwrap_or(b'?') as char;
                return Err(self.error(format!("expected a keyword, found {c:?}")));
            }
            if key.eq_ignore_ascii_case("END") {
                if stack.len() > 1 {
                    let open = stack.last().map(|b| b.name.clone()).unwrap_or_default();
                    return Err(self.error(format!("END inside unclosed OBJECT/GROUP {open}")));
                }
                let root = stack.pop().expect("root block is always on the stack");
                return Ok(Pds3Label { file: self.file.to_path_buf(), root, length: self.pos });
            }
            let upper = key.to_ascii_uppercase();
            let closes = upper == "END_OBJECT" || upper == "END_GROUP";
            self.skip_inline_blank();
            let value = if self.peek() == Some(b'=') {
                self.bump();
                self.skip_blank()?;
                Some(self.value()?)
            } else if closes {
                None
            } else {
                return Err(self.error(format!("expected '=' after {key}")));
            };
            match upper.as_str() {
                "OBJECT" | "GROUP" => {
                    let name = value.as_ref().and_then(|v| v.as_str()).unwrap_or_default().to_string();
                    let kind = if upper == "OBJECT" { BlockKind::Object } else { BlockKind::Group };
                    stack.push(Pds3Block::new(name, kind));
                }
                "END_OBJECT" | "END_GROUP" => {
                    let want = if upper == "END_OBJECT" { BlockKind::Object } else { BlockKind::Group };
                    let block = match stack.pop() {
                        Some(b) if b.kind == want => b,
                        _ => return Err(self.error(format!("{key} without a matching opening"))),
                    };
                    stack.last_mut().expect("root below any closed block").children.push(block);
                }
                _ => {
                    let value = value.expect("non-closing statements always have a value");
                    stack.last_mut().expect("root is always on the stack").entries.push((key, value));
                }
            }
        }
    }

    fn skip_inline_blank(&mut self) {
        while matches!(self.peek(), Some(b' ' | b'\t')) {
            self.pos += 1;
        }
    }

    fn value(&mut self) -> Result<Pds3Value, LoadError> {
        match self.peek() {
            Some(b'"') => {
                self.bump();
                let start = self.pos;
                while self.peek().is_some_and(|c| c != b'"') {
                    self.bump();
                }
                if self.peek().is_none() {
                    return Err(self.error("string never closed"));
                }
                let raw = String::from_utf8_lossy(&self.text[start..self.pos]).into_owned();
                self.bump();
                Ok(Pds3Value::Text(fold_lines(&raw)))
            }
            Some(b'\'') => {
                self.bump();
                let start = self.pos;
                while self.peek().is_some_and(|c| c != b'\'' && c != b'\n') {
                    self.bump();
                }
                if self.peek() != Some(b'\'') {
                    return Err(self.error("quoted literal never closed"));
                }
                let raw = String::from_utf8_lossy(&self.text[start..self.pos]).into_owned();
                self.bump();
                Ok(Pds3Value::Symbol(raw))
            }
            Some(open @ (b'(' | b'{')) => {
                let close = if open == b'(' { b')' } else { b'}' };
                self.bump();
                let mut items = Vec::new();
                loop {
                    self.skip_blank()?;
                    match self.peek() {
                        Some(c) if c == close => {
                            self.bump();
                            return Ok(Pds3Value::Sequence(items));
                        }
                        Some(b',') => {
                            self.bump();
                        }
                        Some(_) => items.push(self.value()?),
                        None => return Err(self.error("list never closed")),
                    }
                }
            }
            Some(_) => {
                let start = self.pos;
                while self.peek().is_some_and(|c| {
                    !(c.is_ascii_whitespace() || matches!(c, b',' | b')' | b'}' | b'<' | b'=' | 0))
                }) {
                    self.bump();
                }
                let token = String::from_utf8_lossy(&self.text[start..self.pos]).into_owned();
                if token.is_empty() {
                    return Err(self.error("missing value"));
                }
                self.skip_inline_blank();
                let unit = if self.peek() == Some(b'<') {
                    self.bump();
                    let s = self.pos;
                    while self.peek().is_some_and(|c| c != b'>' && c != b'\n') {
                        self.bump();
                    }
                    if self.peek() != Some(b'>') {
                        return Err(self.error("unit never closed with '>'"));
                    }
                    let unit = String::from_utf8_lossy(&self.text[s..self.pos]).trim().to_string();
                    self.bump();
                    Some(unit)
                } else {
                    None
                };
                Ok(match parse_number(&token) {
                    Some(value) => Pds3Value::Number { value, unit },
                    None => Pds3Value::Symbol(token),
                })
            }
            None => Err(self.error("missing value at end of label")),
        }
    }
}

/// Folds a multi-line string: each line break and the indentation around it become one space.
fn fold_lines(raw: &str) -> String {
    let mut out = String::with_capacity(raw.len());
    for (i, line) in raw.split('\n').enumerate() {
        let line = if i == 0 { line.trim_end() } else { line.trim() };
        if i > 0 && !out.is_empty() && !line.is_empty() {
            out.push(' ');
        }
        out.push_str(line.trim_end_matches('\r'));
    }
    out
}

/// A decimal number or a based integer (`radix#digits#`); `None` for any other token.
fn parse_number(token: &str) -> Option<f64> {
    let first = token.chars().next()?;
    if !(first.is_ascii_digit() || matches!(first, '+' | '-' | '.')) {
        return None;
    }
    if let Some((radix, rest)) = token.split_once('#') {
        let digits = rest.strip_suffix('#')?;
        let (sign, digits) = match digits.strip_prefix('-') {
            Some(d) => (-1.0, d),
            None => (1.0, digits.strip_prefix('+').unwrap_or(digits)),
        };
        let radix: u32 = radix.parse().ok().filter(|r| (2..=16).contains(r))?;
        return i64::from_str_radix(digits, radix).ok().map(|v| sign * v as f64);
    }
    // Dates such as 2012-08-30T17:59 start with a digit but are not numbers.
    token.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// How an image's samples are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleType {
    /// Two's-complement integers.
    SignedInt {
        /// Most significant byte first.
        big_endian: bool,
    },
    /// Unsigned integers.
    UnsignedInt {
        /// Most significant byte first.
        big_endian: bool,
    },
    /// IEEE 754 floats.
    Float {
        /// Most significant byte first.
        big_endian: bool,
    },
}

impl SampleType {
    /// The sample type of a PDS3 `SAMPLE_TYPE` name, if supported.
    pub fn from_pds(name: &str) -> Option<Self> {
        let be = true;
        Some(match name.to_ascii_uppercase().as_str() {
            "MSB_INTEGER" | "INTEGER" | "SUN_INTEGER" | "MAC_INTEGER" => Self::SignedInt { big_endian: be },
            "LSB_INTEGER" | "PC_INTEGER" | "VAX_INTEGER" => Self::SignedInt { big_endian: !be },
            "MSB_UNSIGNED_INTEGER" | "UNSIGNED_INTEGER" | "SUN_UNSIGNED_INTEGER" | "MAC_UNSIGNED_INTEGER" => {
                Self::UnsignedInt { big_endian: be }
            }
            "LSB_UNSIGNED_INTEGER" | "PC_UNSIGNED_INTEGER" | "VAX_UNSIGNED_INTEGER" => {
                Self::UnsignedInt { big_endian: !be }
            }
            "IEEE_REAL" | "FLOAT" | "REAL" | "SUN_REAL" | "MAC_REAL" => Self::Float { big_endian: be },
            "PC_REAL" => Self::Float { big_endian: !be },
            _ => return None,
        })
    }
}

/// An IMAGE object of a PDS3 product, decoded (first band only).
#[derive(Clone, Debug, PartialEq)]
pub struct Pds3Image {
    /// The product's label.
    pub label: Pds3Label,
    /// The file the pixels were read from.
    pub data_file: PathBuf,
    /// Number of lines (rows), line 0 first as stored (north first for maps).
    pub lines: usize,
    /// Samples per line.
    pub line_samples: usize,
    /// Storage type of the samples.
    pub sample_type: SampleType,
    /// Bits per sample.
    pub sample_bits: u32,
    /// Pixel values, line-major: raw sample & SAMPLE_BIT_MASK, times SCALING_FACTOR, plus
    /// OFFSET; NaN where the raw sample equals MISSING_CONSTANT.
    pub values: Vec<f32>,
}

impl Pds3Image {
    /// Reads a product from its attached-label file or from its detached `.lbl`.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, LoadError> {
        let label = Pds3Label::open(path)?;
        Self::from_label(label)
    }

    /// Reads the IMAGE object a label points to.
    pub fn from_label(label: Pds3Label) -> Result<Self, LoadError> {
        let file = label.file.clone();
        let f = file.as_path();
        let image = label.block("IMAGE").filter(|b| b.kind == BlockKind::Object);
        let image = image.ok_or_else(|| LoadError::missing(f, "OBJECT = IMAGE"))?;
        let count = |key: &str| -> Result<usize, LoadError> {
            let v = image.get_f64(key).ok_or_else(|| LoadError::missing(f, format!("IMAGE.{key}")))?;
            if v >= 0.0 && v.fract() == 0.0 && v < 1e9 {
                Ok(v as usize)
            } else {
                Err(LoadError::invalid(f, format!("IMAGE.{key}"), format!("{v} is not a count")))
            }
        };
        let optional_count = |key: &str, default: usize| -> Result<usize, LoadError> {
            if image.get(key).is_some() { count(key) } else { Ok(default) }
        };
        let lines = count("LINES")?;
        let line_samples = count("LINE_SAMPLES")?;
        let sample_bits = count("SAMPLE_BITS")? as u32;
        let bands = optional_count("BANDS", 1)?;
        let prefix = optional_count("LINE_PREFIX_BYTES", 0)?;
        let suffix = optional_count("LINE_SUFFIX_BYTES", 0)?;
        let type_name =
            image.get_str("SAMPLE_TYPE").ok_or_else(|| LoadError::missing(f, "IMAGE.SAMPLE_TYPE"))?;
        let sample_type = SampleType::from_pds(type_name)
            .ok_or_else(|| LoadError::unsupported(f, format!("IMAGE.SAMPLE_TYPE {type_name}")))?;
        let width_ok = match sample_type {
            SampleType::Float { .. } => matches!(sample_bits, 32 | 64),
            _ => matches!(sample_bits, 8 | 16 | 32),
        };
        if !width_ok {
            return Err(LoadError::unsupported(
                f,
                format!("IMAGE.SAMPLE_BITS {sample_bits} for {type_name}"),
            ));
        }
        if bands > 1 {
            let storage = image.get_str("BAND_STORAGE_TYPE").unwrap_or("BAND_SEQUENTIAL");
            if !storage.eq_ignore_ascii_case("BAND_SEQUENTIAL") {
                return Err(LoadError::unsupported(f, format!("IMAGE.BAND_STORAGE_TYPE {storage}")));
            }
        }
        let scale = image.get_f64("SCALING_FACTOR").unwrap_or(1.0);
        let offset = image.get_f64("OFFSET").unwrap_or(0.0);
        let missing = image.get_f64("MISSING_CONSTANT");
        let mask = image.get_f64("SAMPLE_BIT_MASK").map(|m| m as u64);

        let (data_file, start) = resolve_pointer(&label, "^IMAGE")?;
        let bytes_per_sample = (sample_bits / 8) as usize;
        let line_bytes = prefix + line_samples * bytes_per_sample + suffix;
        // The samples (f32) and raw bytes this label asks for, against the memory ceiling, before
        // reading; `read_range` then checks the bytes against the file's length.
        for (dims, size) in [([lines as u64, line_samples as u64], 4), ([lines as u64, line_bytes as u64], 1)]
        {
            rovernav_core::limits::checked_elements(&dims, size, None)
                .map_err(|why| LoadError::invalid(f, "IMAGE.LINES/LINE_SAMPLES", why))?;
        }
        let needed = (line_bytes as u64) * lines as u64;
        let raw = read_range(&data_file, start, needed, "IMAGE")?;

        let mut values = Vec::with_capacity(lines * line_samples);
        for line in raw.chunks_exact(line_bytes.max(1)).take(lines) {
            let samples = &line[prefix..prefix + line_samples * bytes_per_sample];
            for s in samples.chunks_exact(bytes_per_sample) {
                let v = decode_sample(s, sample_type, mask);
                let is_missing = missing.is_some_and(|m| v == m);
                values.push(if is_missing { f32::NAN } else { (v * scale + offset) as f32 });
            }
        }
        Ok(Self { label, data_file, lines, line_samples, sample_type, sample_bits, values })
    }

    /// The value at (line, sample), 0-based.
    pub fn value(&self, line: usize, sample: usize) -> Option<f32> {
        (line < self.lines && sample < self.line_samples)
            .then(|| self.values[line * self.line_samples + sample])
    }

    /// Smallest and largest value, ignoring missing samples.
    pub fn min_max(&self) -> Option<(f32, f32)> {
        min_max_ignoring_nan(&self.values)
    }

    /// The label's own `MINIMUM` and `MAXIMUM` of the IMAGE object, when it gives them.
    pub fn label_min_max(&self) -> Option<(f64, f64)> {
        let image = self.label.block("IMAGE")?;
        Some((image.get_f64("MINIMUM")?, image.get_f64("MAXIMUM")?))
    }
}

fn decode_sample(s: &[u8], ty: SampleType, mask: Option<u64>) -> f64 {
    let unsigned = |big: bool| -> u64 {
        let mut v = 0u64;
        if big {
            s.iter().for_each(|&b| v = (v << 8) | b as u64);
        } else {
            s.iter().rev().for_each(|&b| v = (v << 8) | b as u64);
        }
        v
    };
    let bits = 8 * s.len() as u32;
    match ty {
        SampleType::UnsignedInt { big_endian } => (unsigned(big_endian) & mask.unwrap_or(u64::MAX)) as f64,
        SampleType::SignedInt { big_endian } => {
            let u = unsigned(big_endian);
            // Sign-extend from the sample width, then apply the mask to the stored bits.
            let signed = ((u << (64 - bits)) as i64) >> (64 - bits);
            match mask {
                Some(m) => (u & m) as f64,
                None => signed as f64,
            }
        }
        SampleType::Float { big_endian } => {
            let u = unsigned(big_endian);
            if bits == 32 { f32::from_bits(u as u32) as f64 } else { f64::from_bits(u) }
        }
    }
}

/// The file and byte offset a pointer such as `^IMAGE` designates.
fn resolve_pointer(label: &Pds3Label, key: &str) -> Result<(PathBuf, u64), LoadError> {
    let f = label.file.as_path();
    let pointer = label.get(key).ok_or_else(|| LoadError::missing(f, key))?;
    let record_bytes = || -> Result<u64, LoadError> {
        let v = label.root.get_f64("RECORD_BYTES").ok_or_else(|| LoadError::missing(f, "RECORD_BYTES"))?;
        if v >= 1.0 && v.fract() == 0.0 {
            Ok(v as u64)
        } else {
            Err(LoadError::invalid(f, "RECORD_BYTES", format!("{v} is not a positive count")))
        }
    };
    // Records and byte positions in pointers are 1-based.
    let location = |v: &Pds3Value| -> Result<u64, LoadError> {
        match v {
            Pds3Value::Number { value, unit } if *value >= 1.0 && value.fract() == 0.0 => {
                if unit.as_deref().is_some_and(|u| u.eq_ignore_ascii_case("BYTES")) {
                    Ok(*value as u64 - 1)
                } else {
                    Ok((*value as u64 - 1).saturating_mul(record_bytes()?))
                }
            }
            other => Err(LoadError::invalid(f, key, format!("bad location {other:?}"))),
        }
    };
    match pointer {
        Pds3Value::Number { .. } => Ok((label.file.clone(), location(pointer)?)),
        Pds3Value::Text(name) | Pds3Value::Symbol(name) => Ok((find_sibling(f, name)?, 0)),
        Pds3Value::Sequence(items) => match &items[..] {
            [name, at] => {
                let name = name
                    .as_str()
                    .ok_or_else(|| LoadError::invalid(f, key, "first item is not a file name"))?;
                Ok((find_sibling(f, name)?, location(at)?))
            }
            [name] => {
                let name =
                    name.as_str().ok_or_else(|| LoadError::invalid(f, key, "item is not a file name"))?;
                Ok((find_sibling(f, name)?, 0))
            }
            _ => Err(LoadError::invalid(f, key, format!("{} items, need 1 or 2", items.len()))),
        },
    }
}

/// A file named in a label, looked up in the label's folder, ignoring case if need be.
fn find_sibling(label_file: &Path, name: &str) -> Result<PathBuf, LoadError> {
    let dir = label_file.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let exact = dir.join(name);
    if exact.is_file() {
        return Ok(exact);
    }
    let entries = std::fs::read_dir(dir).map_err(|e| LoadError::io(dir, e))?;
    for entry in entries.flatten() {
        if entry.file_name().to_string_lossy().eq_ignore_ascii_case(name) {
            return Ok(entry.path());
        }
    }
    Err(LoadError::invalid(
        label_file,
        "^IMAGE",
        format!("data file {name:?} not found in {}", dir.display()),
    ))
}

/// Reads `needed` bytes from `offset` of a file, or says the file is too short.
fn read_range(file: &Path, offset: u64, needed: u64, what: &str) -> Result<Vec<u8>, LoadError> {
    let mut f = File::open(file).map_err(|e| LoadError::io(file, e))?;
    let actual = f.metadata().map_err(|e| LoadError::io(file, e))?.len();
    if offset.checked_add(needed).is_none_or(|end| end > actual) {
        return Err(LoadError::Truncated {
            file: file.to_path_buf(),
            what: what.into(),
            needed,
            offset,
            actual,
        });
    }
    f.seek(SeekFrom::Start(offset)).map_err(|e| LoadError::io(file, e))?;
    let mut buf = vec![0u8; needed as usize];
    f.read_exact(&mut buf).map_err(|e| LoadError::io(file, e))?;
    Ok(buf)
}

/// A global (or regional) map-projected elevation image in simple cylindrical projection,
/// queried by planetocentric latitude and east longitude (degrees), e.g. the MOLA MEGDR.
#[derive(Clone, Debug, PartialEq)]
pub struct GlobalDem {
    /// The image (values in metres after scaling).
    pub image: Pds3Image,
    /// Pixels per degree (MAP_RESOLUTION).
    pub pixels_per_degree: f64,
    /// LINE_PROJECTION_OFFSET: 1-based line coordinate of the equator.
    pub line_projection_offset: f64,
    /// SAMPLE_PROJECTION_OFFSET: 1-based sample coordinate of CENTER_LONGITUDE.
    pub sample_projection_offset: f64,
    /// CENTER_LONGITUDE (deg east).
    pub center_longitude: f64,
    /// Reference radius (m), from A_AXIS_RADIUS.
    pub radius_m: f64,
    /// Whether longitudes in the label increase westwards.
    pub west_positive: bool,
}

impl GlobalDem {
    /// Opens a PDS3 map product (label file or attached-label image).
    pub fn open(path: impl AsRef<Path>) -> Result<Self, LoadError> {
        Self::from_image(Pds3Image::open(path)?)
    }

    /// Reads the map projection of an already loaded image.
    pub fn from_image(image: Pds3Image) -> Result<Self, LoadError> {
        let f = image.label.file.clone();
        let f = f.as_path();
        let proj = image
            .label
            .block("IMAGE_MAP_PROJECTION")
            .ok_or_else(|| LoadError::missing(f, "OBJECT = IMAGE_MAP_PROJECTION"))?;
        let field = |key: &str| {
            proj.get_f64(key).ok_or_else(|| LoadError::missing(f, format!("IMAGE_MAP_PROJECTION.{key}")))
        };
        let kind = proj.get_str("MAP_PROJECTION_TYPE").unwrap_or("");
        let center_latitude = proj.get_f64("CENTER_LATITUDE").unwrap_or(0.0);
        let cylindrical = kind.eq_ignore_ascii_case("SIMPLE CYLINDRICAL")
            || (kind.eq_ignore_ascii_case("EQUIRECTANGULAR") && center_latitude == 0.0);
        if !cylindrical {
            return Err(LoadError::unsupported(f, format!("MAP_PROJECTION_TYPE {kind:?}")));
        }
        let pixels_per_degree = field("MAP_RESOLUTION")?;
        if !(pixels_per_degree.is_finite() && pixels_per_degree > 0.0) {
            return Err(LoadError::invalid(f, "IMAGE_MAP_PROJECTION.MAP_RESOLUTION", "not positive"));
        }
        let radius_km = proj.get_f64("A_AXIS_RADIUS").unwrap_or(3396.19);
        let unit_is_km = !matches!(proj.get("A_AXIS_RADIUS"), Some(Pds3Value::Number { unit: Some(u), .. }) if u.eq_ignore_ascii_case("M") || u.eq_ignore_ascii_case("METER"));
        let west_positive =
            proj.get_str("POSITIVE_LONGITUDE_DIRECTION").is_some_and(|d| d.eq_ignore_ascii_case("WEST"));
        Ok(Self {
            pixels_per_degree,
            line_projection_offset: field("LINE_PROJECTION_OFFSET")?,
            sample_projection_offset: field("SAMPLE_PROJECTION_OFFSET")?,
            center_longitude: field("CENTER_LONGITUDE")?,
            radius_m: if unit_is_km { radius_km * 1000.0 } else { radius_km },
            west_positive,
            image,
        })
    }

    /// Elevation (m) at a latitude and east longitude (deg), bilinear between pixel centres,
    /// wrapping in longitude when the map spans 360 degrees; `None` outside or on missing data.
    pub fn height_at_latlon(&self, lat_deg: f64, lon_deg_east: f64) -> Option<f64> {
        let (lines, samples) = (self.image.lines, self.image.line_samples);
        if lines == 0 || samples == 0 || !lat_deg.is_finite() || !lon_deg_east.is_finite() {
            return None;
        }
        let lon = if self.west_positive { -lon_deg_east } else { lon_deg_east };
        let line = self.line_projection_offset - lat_deg * self.pixels_per_degree - 1.0;
        let global = (samples as f64 / self.pixels_per_degree - 360.0).abs() < 1e-6;
        let mut sample =
            self.sample_projection_offset + self.pixels_per_degree * (lon - self.center_longitude) - 1.0;
        if global {
            sample = sample.rem_euclid(samples as f64);
        }
        if !(-0.5..=lines as f64 - 0.5).contains(&line) {
            return None;
        }
        if !global && !(-0.5..=samples as f64 - 0.5).contains(&sample) {
            return None;
        }
        let line = line.clamp(0.0, (lines - 1) as f64);
        let l0 = (line.floor() as usize).min(lines.saturating_sub(2));
        let l1 = (l0 + 1).min(lines - 1);
        let tl = line - l0 as f64;
        let (s0, s1, ts) = if global {
            let s0 = (sample.floor() as usize) % samples;
            (s0, (s0 + 1) % samples, sample - sample.floor())
        } else {
            let s = sample.clamp(0.0, (samples - 1) as f64);
            let s0 = (s.floor() as usize).min(samples.saturating_sub(2));
            (s0, (s0 + 1).min(samples - 1), s - s0 as f64)
        };
        let v = |l: usize, s: usize| self.image.values[l * samples + s] as f64;
        let h = (v(l0, s0) * (1.0 - ts) + v(l0, s1) * ts) * (1.0 - tl)
            + (v(l1, s0) * (1.0 - ts) + v(l1, s1) * ts) * tl;
        h.is_finite().then_some(h)
    }

    /// Lowest and highest elevation in the map (m), ignoring missing data.
    pub fn min_max(&self) -> Option<(f32, f32)> {
        self.image.min_max()
    }
}

/// A CAHVOR camera model (Yakimovsky-Cunningham CAHV plus Gennery's radial distortion), in
/// the frame the label names: C centre, A axis, H and V horizontal and vertical image vectors,
/// O optical axis, R radial distortion coefficients.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CahvorModel {
    /// Camera centre.
    pub c: [f64; 3],
    /// Pointing axis (unit).
    pub a: [f64; 3],
    /// Horizontal image vector.
    pub h: [f64; 3],
    /// Vertical image vector.
    pub v: [f64; 3],
    /// Optical axis of the distortion (unit).
    pub o: [f64; 3],
    /// Radial distortion coefficients r0, r1, r2.
    pub r: [f64; 3],
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl CahvorModel {
    /// The image point (sample, line) where the pointing axis meets the image: (H.A, V.A).
    pub fn image_centre(&self) -> (f64, f64) {
        (dot(self.h, self.a), dot(self.v, self.a))
    }

    /// Projects a 3-D point to image (sample, line); `None` for points behind the camera.
    pub fn project(&self, p: [f64; 3]) -> Option<(f64, f64)> {
        let d = [p[0] - self.c[0], p[1] - self.c[1], p[2] - self.c[2]];
        let zeta = dot(d, self.o);
        if zeta <= 0.0 {
            return None;
        }
        let lambda = [d[0] - zeta * self.o[0], d[1] - zeta * self.o[1], d[2] - zeta * self.o[2]];
        let tau = dot(lambda, lambda) / (zeta * zeta);
        let mu = self.r[0] + self.r[1] * tau + self.r[2] * tau * tau;
        let q = [d[0] + mu * lambda[0], d[1] + mu * lambda[1], d[2] + mu * lambda[2]];
        let depth = dot(q, self.a);
        (depth > 0.0).then(|| (dot(q, self.h) / depth, dot(q, self.v) / depth))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Pds3Label, LoadError> {
        Pds3Label::parse(Path::new("test.lbl"), text)
    }

    #[test]
    fn parses_objects_groups_lists_units_and_comments() {
        let text = "PDS_VERSION_ID = PDS3\r\n/* a comment */\nRECORD_BYTES = 2048\n^IMAGE = (\"X.IMG\", 12 <BYTES>)\n\
                    NOTE = \"two\n   lines\"\nOBJECT = IMAGE\n  LINES = 3\n  MASK = 2#0000111111111111#\n\
                    GROUP = G\n  V = (1.5, -2,\n 3e2)\n  T = 2012-08-30T17:59:23.435\n END_GROUP = G\nEND_OBJECT\nEND\n\x00\x01binary";
        let label = parse(text).unwrap();
        assert_eq!(label.get("RECORD_BYTES").and_then(Pds3Value::as_f64), Some(2048.0));
        assert_eq!(label.get("note").and_then(Pds3Value::as_str), Some("two lines"));
        let ptr = label.get("^IMAGE").unwrap();
        assert_eq!(
            ptr,
            &Pds3Value::Sequence(vec![
                Pds3Value::Text("X.IMG".into()),
                Pds3Value::Number { value: 12.0, unit: Some("BYTES".into()) }
            ])
        );
        let image = label.block("IMAGE").unwrap();
        assert_eq!(image.get_f64("LINES"), Some(3.0));
        assert_eq!(image.get_f64("MASK"), Some(4095.0));
        let g = label.block("G").unwrap();
        assert_eq!(g.get("V").unwrap().as_f64_vec(), Some(vec![1.5, -2.0, 300.0]));
        assert_eq!(g.get_str("T"), Some("2012-08-30T17:59:23.435"));
        assert!(label.flatten().iter().any(|(k, _)| k == "IMAGE.G.V"));
        assert_eq!(&text[label.length - 3..label.length], "END");
    }

    #[test]
    fn syntax_errors_name_the_line() {
        let err = parse("A = 1\nB = (1, 2\n").unwrap_err();
        assert!(matches!(err, LoadError::Syntax { .. }), "{err}");
        let err = parse("A = 1\nOBJECT = X\nEND\n").unwrap_err();
        assert!(matches!(err, LoadError::Syntax { line: 3, .. }), "{err}");
        let err = parse("A = 1\nB 2\nEND").unwrap_err();
        assert!(matches!(err, LoadError::Syntax { line: 2, .. }), "{err}");
        assert!(parse("A = 1\n").is_err());
        assert!(parse("END_GROUP = X\nEND").is_err());
    }

    #[test]
    fn samples_decode_by_type_and_mask() {
        let be = true;
        assert_eq!(decode_sample(&[0xff, 0xfe], SampleType::SignedInt { big_endian: be }, None), -2.0);
        assert_eq!(decode_sample(&[0xfe, 0xff], SampleType::SignedInt { big_endian: !be }, None), -2.0);
        assert_eq!(decode_sample(&[0xff, 0xfe], SampleType::UnsignedInt { big_endian: be }, None), 65534.0);
        assert_eq!(
            decode_sample(&[0xff, 0xfe], SampleType::UnsignedInt { big_endian: be }, Some(0x0fff)),
            4094.0
        );
        let f = 1.5f32.to_le_bytes();
        assert_eq!(decode_sample(&f, SampleType::Float { big_endian: !be }, None), 1.5);
        let f = (-0.25f32).to_be_bytes();
        assert_eq!(decode_sample(&f, SampleType::Float { big_endian: be }, None), -0.25);
    }

    #[test]
    fn cahv_projection_of_axis_and_of_an_offset_point() {
        // An ideal camera at the origin looking along +x, 100 px focal length, centre (50, 40),
        // image x to the right (-y) and lines downwards (-z).
        let model = CahvorModel {
            c: [0.0; 3],
            a: [1.0, 0.0, 0.0],
            h: [50.0, -100.0, 0.0],
            v: [40.0, 0.0, -100.0],
            o: [1.0, 0.0, 0.0],
            r: [0.0; 3],
        };
        assert_eq!(model.image_centre(), (50.0, 40.0));
        assert_eq!(model.project([2.0, 0.0, 0.0]), Some((50.0, 40.0)));
        // 0.1 rad to the left and up: 100 * 0.1 px from the centre (pinhole).
        let (s, l) = model.project([10.0, 1.0, 1.0]).unwrap();
        assert!((s - 40.0).abs() < 1e-9 && (l - 30.0).abs() < 1e-9);
        assert_eq!(model.project([-1.0, 0.0, 0.0]), None);
    }
}
