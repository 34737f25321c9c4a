//! The parameters of a design: each one's range and name, written once beside its default in its
//! method's `params.rs` and read by the method's `check()`, the command line, the design link and
//! the app's sliders; and how a method's parameters are written to and read from a design link
//! ([`LinkFields`]).

use std::fmt::Display;

/// An inclusive range a parameter must lie in, with its name: the one check of that parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamRange<T> {
    pub name: &'static str,
    pub lo: T,
    pub hi: T,
    /// Why the upper bound is where it is, said when a value is above it.
    pub above: Option<&'static str>,
}

impl<T: Copy> ParamRange<T> {
    pub const fn new(name: &'static str, lo: T, hi: T) -> Self {
        Self { name, lo, hi, above: None }
    }

    /// The range with the reason for its upper bound.
    pub const fn bounded_by(self, reason: &'static str) -> Self {
        Self { above: Some(reason), ..self }
    }
}

impl<T: PartialOrd + Copy + Display> ParamRange<T> {
    pub fn contains(&self, x: T) -> bool {
        self.lo <= x && x <= self.hi
    }

    /// `x`, or why it is outside.
    pub fn check(&self, x: T) -> Result<T, ParamError> {
        if self.contains(x) {
            Ok(x)
        } else {
            let above = self.above.filter(|_| x > self.hi);
            Err(ParamError { name: self.name, value: x.to_string(), lo: self.lo.to_string(), hi: self.hi.to_string(), above })
        }
    }

    pub fn range(&self) -> std::ops::RangeInclusive<T> {
        self.lo..=self.hi
    }
}

impl ParamRange<f64> {
    /// Parses and checks a number typed by a user.
    pub fn parse(&self, s: &str) -> Result<f64, String> {
        let x = s.trim().parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| format!("'{s}' is not a number"))?;
        self.check(x).map_err(|e| e.to_string())
    }
}

impl ParamRange<usize> {
    /// Parses and checks a count typed by a user.
    pub fn parse(&self, s: &str) -> Result<usize, String> {
        let n = s.trim().parse::<usize>().map_err(|_| format!("'{s}' is not a whole number"))?;
        self.check(n).map_err(|e| e.to_string())
    }
}

/// A parameter outside its range.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamError {
    pub name: &'static str,
    pub value: String,
    pub lo: String,
    pub hi: String,
    /// Why the upper bound is there, when the value is above it.
    pub above: Option<&'static str>,
}

impl Display for ParamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.above {
            Some(why) => write!(f, "{} {} is {why}; at most {}", self.name, self.value, self.hi),
            None => write!(f, "{} {} is outside [{}, {}]", self.name, self.value, self.lo, self.hi),
        }
    }
}

impl std::error::Error for ParamError {}

/// A method's parameters in a design link: every parameter that defines a design, each under its
/// key, and read back to the same value.
pub trait LinkFields {
    /// Writes the fields, in a fixed order.
    fn write_link(&self, link: &mut LinkWriter);
    /// Reads the fields `link` has, each checked against its range; where a field is not valid
    /// the parameter keeps its value and the reader marks the field.
    fn read_link(&mut self, link: &mut LinkReader);
}

/// The fields of a link as they are written: `&key=value`.
#[derive(Default)]
pub struct LinkWriter {
    pub text: String,
}

impl LinkWriter {
    pub fn text(&mut self, key: &str, value: &str) {
        self.text += &format!("&{key}={value}");
    }

    /// A number exactly: the shorter of the plain and the exponent form of the shortest
    /// round-trip digits (so `rtol=1e-5` reads back as 1e-5, never as 0).
    pub fn number(&mut self, key: &str, x: f64) {
        self.text(key, &number_text(x));
    }

    pub fn count(&mut self, key: &str, n: usize) {
        self.text(key, &n.to_string());
    }

    pub fn flag(&mut self, key: &str, on: bool) {
        self.text(key, if on { "1" } else { "0" });
    }
}

/// A number exactly, as short as it reads back (see [`LinkWriter::number`]).
pub fn number_text(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let (plain, exp) = (format!("{x}"), format!("{x:e}"));
    if exp.len() < plain.len() {
        exp
    } else {
        plain
    }
}

/// What became of a field of a link being read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldStatus {
    Unread,
    Read,
    /// Read, but its value was not valid: the parameter kept its value.
    Invalid,
}

/// The fields of a link being read, and what became of each.
pub struct LinkReader {
    pairs: Vec<(String, String)>,
    status: Vec<FieldStatus>,
}

impl LinkReader {
    pub fn new(pairs: Vec<(String, String)>) -> Self {
        let status = vec![FieldStatus::Unread; pairs.len()];
        Self { pairs, status }
    }

    /// The value of `key` (the last one when it repeats), marked as read.
    pub fn get(&mut self, key: &str) -> Option<String> {
        let mut value = None;
        for (i, (k, v)) in self.pairs.iter().enumerate() {
            if k == key {
                self.status[i] = FieldStatus::Read;
                value = Some((i, v.clone()));
            }
        }
        value.map(|(_, v)| v)
    }

    /// The value of `key` parsed by `parse`; an invalid value is marked [`FieldStatus::Invalid`].
    pub fn parsed<T>(&mut self, key: &str, parse: impl Fn(&str) -> Option<T>) -> Option<T> {
        let v = self.get(key)?;
        let x = parse(&v);
        if x.is_none() {
            if let Some(i) = self.pairs.iter().rposition(|(k, _)| k == key) {
                self.status[i] = FieldStatus::Invalid;
            }
        }
        x
    }

    pub fn number(&mut self, key: &str, range: ParamRange<f64>) -> Option<f64> {
        self.parsed(key, |v| range.parse(v).ok())
    }

    pub fn count(&mut self, key: &str, range: ParamRange<usize>) -> Option<usize> {
        self.parsed(key, |v| range.parse(v).ok())
    }

    /// "0" or "1".
    pub fn flag(&mut self, key: &str) -> Option<bool> {
        self.parsed(key, |v| match v {
            "0" => Some(false),
            "1" => Some(true),
            _ => None,
        })
    }

    /// Sets `into` to the number under `key`, when the link has a valid one.
    pub fn set_number(&mut self, key: &str, range: ParamRange<f64>, into: &mut f64) {
        if let Some(x) = self.number(key, range) {
            *into = x;
        }
    }

    /// Sets `into` to the count under `key`, when the link has a valid one.
    pub fn set_count(&mut self, key: &str, range: ParamRange<usize>, into: &mut usize) {
        if let Some(n) = self.count(key, range) {
            *into = n;
        }
    }

    /// Sets `into` to the flag under `key`, when the link has a valid one.
    pub fn set_flag(&mut self, key: &str, into: &mut bool) {
        if let Some(x) = self.flag(key) {
            *into = x;
        }
    }

    /// Sets `into` to what `parse` makes of the value under `key`, when it makes something.
    pub fn set_parsed<T>(&mut self, key: &str, parse: impl Fn(&str) -> Option<T>, into: &mut T) {
        if let Some(x) = self.parsed(key, parse) {
            *into = x;
        }
    }

    /// Every field in the link's order, with what became of it.
    pub fn fields(&self) -> impl Iterator<Item = (&str, &str, FieldStatus)> {
        self.pairs.iter().zip(&self.status).map(|((k, v), s)| (k.as_str(), v.as_str(), *s))
    }

    /// A reader of the same fields that has read nothing yet (to learn which keys a parser knows).
    pub fn fresh(&self) -> LinkReader {
        LinkReader::new(self.pairs.clone())
    }

    /// Marks the fields another reader of the same link read (valid or not) as read here, where
    /// this one left them unread.
    pub fn mark_known(&mut self, other: &LinkReader) {
        for (s, o) in self.status.iter_mut().zip(&other.status) {
            if *s == FieldStatus::Unread && *o != FieldStatus::Unread {
                *s = FieldStatus::Read;
            }
        }
    }
}

/// A link value with every byte but letters, digits and `-_.~` percent-encoded.
pub fn percent_encode(s: &str) -> String {
    let mut out = String::new();
    for b in s.bytes() {
        if b.is_ascii_alphanumeric() || b"-_.~".contains(&b) {
            out.push(b as char);
        } else {
            out += &format!("%{b:02X}");
        }
    }
    out
}

/// A link value decoded (`+` is a space; a `%` without two hex digits stays as it is).
pub fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(if b[i] == b'+' { b' ' } else { b[i] });
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}
