//! Model units: what one coordinate unit of the design is in the real world, and lengths written
//! with a unit ("2mm", "0.5 in"). The geometry itself is unitless; units turn a fabrication
//! tolerance into model units and label the lengths shown and written.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// The length one model unit stands for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Units {
    #[default]
    M,
    Cm,
    Mm,
    Ft,
    In,
}

impl Units {
    pub const ALL: [Units; 5] = [Units::M, Units::Cm, Units::Mm, Units::Ft, Units::In];

    /// Metres in one unit.
    pub fn metres(self) -> f64 {
        match self {
            Units::M => 1.0,
            Units::Cm => 0.01,
            Units::Mm => 0.001,
            Units::Ft => 0.3048,
            Units::In => 0.0254,
        }
    }

    /// The symbol ("m", "mm", "ft"), as in a design link and the CLI.
    pub fn symbol(self) -> &'static str {
        match self {
            Units::M => "m",
            Units::Cm => "cm",
            Units::Mm => "mm",
            Units::Ft => "ft",
            Units::In => "in",
        }
    }

    /// A unit by its English name, as CAD files write it ("Millimeters", "feet", "inch"); None
    /// for other systems.
    pub fn from_name(name: &str) -> Option<Units> {
        let n = name.trim().to_ascii_lowercase();
        let n = n.strip_suffix('s').unwrap_or(&n).replace("metre", "meter");
        match n.as_str() {
            "meter" => Some(Units::M),
            "centimeter" => Some(Units::Cm),
            "millimeter" => Some(Units::Mm),
            "foot" | "feet" => Some(Units::Ft),
            "inche" | "inch" => Some(Units::In),
            _ => None,
        }
    }

    /// A length of `self` in model units `to`.
    pub fn convert(self, length: f64, to: Units) -> f64 {
        length * self.metres() / to.metres()
    }
}

impl fmt::Display for Units {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.symbol())
    }
}

/// `value` with four significant digits and the unit symbol ("2.000 mm", "0.00005000 m"), in
/// scientific notation below 1e-6 ("4.0e-15 m": rounding, not a length).
pub fn format_length(value: f64, units: Units) -> String {
    if !value.is_finite() || value == 0.0 {
        return format!("{value} {units}");
    }
    if value.abs() < 1e-6 {
        return format!("{value:.1e} {units}");
    }
    let decimals = (3 - value.abs().log10().floor() as i32).clamp(0, 15) as usize;
    format!("{value:.decimals$} {units}")
}

/// A text that is no unit or no length.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum UnitsError {
    UnknownUnit(String),
    /// Not a finite number ≥ 0 followed by an optional unit.
    NotALength(String),
}

impl fmt::Display for UnitsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let all: Vec<&str> = Units::ALL.iter().map(|u| u.symbol()).collect();
        match self {
            UnitsError::UnknownUnit(s) => write!(f, "unknown unit {:?}: use one of {}", clip(s), all.join(", ")),
            UnitsError::NotALength(s) => {
                write!(f, "{:?} is not a length: a number ≥ 0, optionally with a unit ({})", clip(s), all.join(", "))
            }
        }
    }
}

impl std::error::Error for UnitsError {}

/// The first 40 characters of a user's text, for a message.
fn clip(s: &str) -> String {
    s.chars().take(40).collect()
}

impl FromStr for Units {
    type Err = UnitsError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim().to_ascii_lowercase();
        Units::ALL.into_iter().find(|u| u.symbol() == t).ok_or_else(|| UnitsError::UnknownUnit(s.to_string()))
    }
}

/// A length as written: a value and, optionally, its unit (None: model units).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Length {
    pub value: f64,
    pub unit: Option<Units>,
}

impl Length {
    pub fn new(value: f64, unit: Units) -> Self {
        Self { value, unit: Some(unit) }
    }

    /// The length in model units `model`.
    pub fn in_model_units(&self, model: Units) -> f64 {
        match self.unit {
            Some(u) => u.convert(self.value, model),
            None => self.value,
        }
    }
}

impl fmt::Display for Length {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.unit {
            Some(u) => write!(f, "{}{}", self.value, u),
            None => write!(f, "{}", self.value),
        }
    }
}

impl FromStr for Length {
    type Err = UnitsError;

    /// "2mm", "2 mm", "0.002m" or "2" (model units).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim();
        let split = t.trim_end_matches(|c: char| c.is_ascii_alphabetic()).len();
        let (number, unit) = t.split_at(split);
        let value: f64 = number.trim().parse().map_err(|_| UnitsError::NotALength(s.to_string()))?;
        if !(value.is_finite() && value >= 0.0) {
            return Err(UnitsError::NotALength(s.to_string()));
        }
        let unit = if unit.is_empty() { None } else { Some(unit.parse()?) };
        Ok(Length { value, unit })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_parse_and_convert() {
        let l: Length = "2mm".parse().unwrap();
        assert_eq!(l, Length::new(2.0, Units::Mm));
        assert!((l.in_model_units(Units::M) - 0.002).abs() < 1e-15);
        assert!((l.in_model_units(Units::In) - 2.0 / 25.4).abs() < 1e-15);
        assert!(("1.5 ft".parse::<Length>().unwrap().in_model_units(Units::In) - 18.0).abs() < 1e-12);
        assert_eq!("3".parse::<Length>().unwrap().in_model_units(Units::Mm), 3.0);
        assert_eq!("2e-3m".parse::<Length>().unwrap(), Length::new(2e-3, Units::M));
        assert!(matches!("2 furlong".parse::<Length>(), Err(UnitsError::UnknownUnit(_))));
        assert!(matches!("-1mm".parse::<Length>(), Err(UnitsError::NotALength(_))));
        assert!(matches!("NaN".parse::<Length>(), Err(UnitsError::NotALength(_))));
        assert_eq!(format_length(2.0, Units::Mm), "2.000 mm");
        assert_eq!(format_length(5e-5, Units::M), "0.00005000 m");
        assert_eq!(format_length(4.2e-15, Units::M), "4.2e-15 m");
        assert_eq!(format_length(1234.5, Units::In), "1234 in");
        for (name, u) in [
            ("Millimeters", Units::Mm),
            ("Meters", Units::M),
            ("centimetres", Units::Cm),
            ("Feet", Units::Ft),
            ("Inches", Units::In),
            ("inch", Units::In),
        ] {
            assert_eq!(Units::from_name(name), Some(u), "{name}");
        }
        assert_eq!(Units::from_name("Microns"), None);
        for u in Units::ALL {
            assert_eq!(u.symbol().parse::<Units>().unwrap(), u);
            let l: Length = format!("{}", Length::new(0.25, u)).parse().unwrap();
            assert_eq!(l, Length::new(0.25, u));
        }
    }
}
