//! Numbers of the run logs that read back whatever their value. JSON has no NaN or
//! infinity and serde_json writes them as `null`, which no float field reads; with
//! `#[serde(with = "crate::log_float")]` a finite number is written as a JSON number
//! (exactly as before) and NaN, +∞ and −∞ as the strings `"NaN"`, `"inf"` and
//! `"-inf"`; either form is read. [`option`] does the same for an `Option` field.

use std::fmt;

use serde::de::{self, Visitor};
use serde::{Deserializer, Serializer};

/// A float type of a log field.
pub(crate) trait LogFloat: Copy {
    /// Writes a finite value as a number of its own width.
    fn serialize_finite<S: Serializer>(self, serializer: S) -> Result<S::Ok, S::Error>;
    fn to_f64(self) -> f64;
    fn from_f64(value: f64) -> Self;
}

impl LogFloat for f64 {
    fn serialize_finite<S: Serializer>(self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_f64(self)
    }
    fn to_f64(self) -> f64 {
        self
    }
    fn from_f64(value: f64) -> Self {
        value
    }
}

impl LogFloat for f32 {
    fn serialize_finite<S: Serializer>(self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_f32(self)
    }
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
    fn from_f64(value: f64) -> Self {
        value as f32
    }
}

pub(crate) fn serialize<T: LogFloat, S: Serializer>(
    value: &T,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    let v = value.to_f64();
    match v {
        _ if v.is_finite() => value.serialize_finite(serializer),
        _ if v.is_nan() => serializer.serialize_str("NaN"),
        f64::INFINITY => serializer.serialize_str("inf"),
        _ => serializer.serialize_str("-inf"),
    }
}

pub(crate) fn deserialize<'de, T: LogFloat, D: Deserializer<'de>>(
    deserializer: D,
) -> Result<T, D::Error> {
    deserializer.deserialize_any(FloatVisitor).map(T::from_f64)
}

struct FloatVisitor;

impl Visitor<'_> for FloatVisitor {
    type Value = f64;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(r#"a number, "NaN", "inf" or "-inf""#)
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<f64, E> {
        Ok(v)
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<f64, E> {
        Ok(v as f64)
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<f64, E> {
        Ok(v as f64)
    }

    fn visit_str<E: de::Error>(self, v: &str) -> Result<f64, E> {
        match v {
            "NaN" => Ok(f64::NAN),
            "inf" => Ok(f64::INFINITY),
            "-inf" => Ok(f64::NEG_INFINITY),
            _ => Err(E::invalid_value(de::Unexpected::Str(v), &self)),
        }
    }
}

/// The same for an `Option` field (`null` is `None`).
pub(crate) mod option {
    use serde::{Deserialize, Deserializer, Serializer};

    use super::LogFloat;

    pub(crate) fn serialize<T: LogFloat, S: Serializer>(
        value: &Option<T>,
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        match value {
            Some(v) => super::serialize(v, serializer),
            None => serializer.serialize_none(),
        }
    }

    pub(crate) fn deserialize<'de, T: LogFloat, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<Option<T>, D::Error> {
        #[derive(Deserialize)]
        struct Wrapped(#[serde(with = "super")] f64);
        let value: Option<Wrapped> = Option::deserialize(deserializer)?;
        Ok(value.map(|Wrapped(v)| T::from_f64(v)))
    }
}

#[cfg(test)]
mod tests {
    use serde::{Deserialize, Serialize};

    #[derive(Debug, Serialize, Deserialize)]
    struct Line {
        #[serde(with = "super")]
        loss: f32,
        #[serde(with = "super")]
        welfare: f64,
        #[serde(default, with = "super::option")]
        share: Option<f64>,
    }

    fn round_trip(line: &Line) -> (String, Line) {
        let text = serde_json::to_string(line).unwrap();
        let back = serde_json::from_str(&text).unwrap();
        (text, back)
    }

    #[test]
    fn finite_numbers_are_written_as_before_and_non_finite_ones_read_back() {
        let line = Line {
            loss: 0.1,
            welfare: 36.64,
            share: Some(0.25),
        };
        let (text, back) = round_trip(&line);
        assert_eq!(text, r#"{"loss":0.1,"welfare":36.64,"share":0.25}"#);
        assert_eq!(
            (back.loss, back.welfare, back.share),
            (0.1, 36.64, Some(0.25))
        );

        let line = Line {
            loss: f32::INFINITY,
            welfare: f64::NAN,
            share: Some(f64::NEG_INFINITY),
        };
        let (text, back) = round_trip(&line);
        assert_eq!(text, r#"{"loss":"inf","welfare":"NaN","share":"-inf"}"#);
        assert!(back.loss == f32::INFINITY && back.welfare.is_nan());
        assert_eq!(back.share, Some(f64::NEG_INFINITY));

        let (_, back) = round_trip(&Line {
            loss: 1.0,
            welfare: 2.0,
            share: None,
        });
        assert_eq!(back.share, None);
        let integers: Line = serde_json::from_str(r#"{"loss":3,"welfare":-4}"#).unwrap();
        assert_eq!(
            (integers.loss, integers.welfare, integers.share),
            (3.0, -4.0, None)
        );
    }

    #[test]
    fn other_strings_and_null_are_errors_that_say_what_is_expected() {
        for bad in [
            r#"{"loss":"nan","welfare":1}"#,
            r#"{"loss":null,"welfare":1}"#,
            r#"{"loss":1,"welfare":"1.5"}"#,
        ] {
            let err = serde_json::from_str::<Line>(bad).unwrap_err().to_string();
            assert!(err.contains(r#""NaN", "inf" or "-inf""#), "{bad}: {err}");
        }
    }
}
