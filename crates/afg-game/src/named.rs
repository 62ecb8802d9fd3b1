//! Enums with names a user types (`"balanced"`, `"bounded"`, `"ddqn"`): one list of
//! values and one spelling each, for the command line, Python and files alike.

use crate::GameError;

/// A unit enum whose values a user names. The names are the enum's serde names, so a
/// value reads the same in a file, on the command line and in Python.
///
/// # Examples
/// ```
/// use afg_game::{Named, Preference};
/// assert_eq!(Preference::from_name("selfish")?, Preference::Selfish);
/// assert_eq!(Preference::Balanced.name(), "balanced");
/// let err = Preference::from_name("greedy").unwrap_err();
/// assert_eq!(err.to_string(), "unknown preference \"greedy\": expected balanced or selfish");
/// # Ok::<(), afg_game::GameError>(())
/// ```
pub trait Named: Copy + PartialEq + 'static {
    /// Every value, in the order a help text lists them.
    const ALL: &'static [Self];
    /// What a value is, for messages ("preference", "units").
    const WHAT: &'static str;

    /// The value's name.
    fn name(self) -> &'static str;

    /// The value named `name`.
    ///
    /// # Errors
    /// [`GameError::UnknownName`], listing the names there are.
    fn from_name(name: &str) -> Result<Self, GameError> {
        Self::ALL
            .iter()
            .copied()
            .find(|v| v.name() == name)
            .ok_or_else(|| GameError::UnknownName {
                what: Self::WHAT,
                name: name.to_owned(),
                expected: names_text(Self::ALL.iter().map(|v| v.name())),
            })
    }
}

/// `a, b or c`.
fn names_text<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let names: Vec<&str> = names.collect();
    match names.split_last() {
        Some((last, [])) => (*last).to_owned(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Preference;

    #[test]
    fn names_are_the_serde_names_and_read_back() {
        for &p in Preference::ALL {
            let serde = serde_json::to_value(p).unwrap();
            assert_eq!(serde.as_str(), Some(p.name()));
            assert_eq!(Preference::from_name(p.name()).unwrap(), p);
        }
        assert_eq!(names_text(["a", "b", "c"].into_iter()), "a, b or c");
    }
}
