//! Arguments from Python read as a Python user writes them, and refused as afg's own
//! errors (`afg.InvalidInputError`, naming the value) instead of PyO3's `TypeError` or
//! `OverflowError`: whole numbers given as ints, numpy integers, bools or floats without
//! a fraction; pairs given as any sequence of two (a tuple, a list, a numpy array);
//! integer vectors and matrices given as lists or numpy arrays of any of those.

use pyo3::prelude::*;
use pyo3::types::PyString;

use crate::bad_input;

/// An integer in any of Python's spellings of one.
fn integer(ob: &Bound<'_, PyAny>) -> PyResult<i128> {
    if let Ok(v) = ob.extract::<i128>() {
        return Ok(v);
    }
    if let Ok(b) = ob.extract::<bool>() {
        return Ok(i128::from(b));
    }
    match ob.extract::<f64>() {
        Ok(f) if f.fract() == 0.0 && f.abs() < 9.0e15 => Ok(f as i128),
        _ => Err(bad_input(format!(
            "expected a whole number, got {}",
            ob.repr()?
        ))),
    }
}

/// The items of a sequence (not a string).
fn items<'py>(ob: &Bound<'py, PyAny>, what: &str) -> PyResult<Vec<Bound<'py, PyAny>>> {
    if ob.is_instance_of::<PyString>() {
        return Err(bad_input(format!(
            "expected {what}, got the string {}",
            ob.repr()?
        )));
    }
    match ob.try_iter() {
        Ok(iter) => iter.collect(),
        Err(_) => Err(bad_input(format!("expected {what}, got {}", ob.repr()?))),
    }
}

/// A whole number from 0 to 2^64 − 1.
pub(crate) struct Whole(pub(crate) u64);

impl<'a, 'py> FromPyObject<'a, 'py> for Whole {
    type Error = PyErr;

    fn extract(ob: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let v = integer(&ob)?;
        u64::try_from(v).map(Whole).map_err(|_| {
            bad_input(format!(
                "expected a whole number from 0 to {}, got {v}",
                u64::MAX
            ))
        })
    }
}

impl Whole {
    /// As a count (refused where it does not fit this machine's `usize`).
    pub(crate) fn count(&self) -> PyResult<usize> {
        usize::try_from(self.0).map_err(|_| bad_input(format!("{} is too large a count", self.0)))
    }
}

/// Two whole numbers, (lo, hi), in any sequence of two.
pub(crate) struct WholePair(pub(crate) usize, pub(crate) usize);

impl<'a, 'py> FromPyObject<'a, 'py> for WholePair {
    type Error = PyErr;

    fn extract(ob: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let two = items(&ob, "two whole numbers (lo, hi)")?;
        let [lo, hi] = two.as_slice() else {
            return Err(bad_input(format!(
                "expected two whole numbers (lo, hi), got {} values",
                two.len()
            )));
        };
        let (lo, hi) = (
            lo.extract::<Whole>()?.count()?,
            hi.extract::<Whole>()?.count()?,
        );
        Ok(WholePair(lo, hi))
    }
}

/// Two numbers, (lo, hi), in any sequence of two.
pub(crate) struct FloatPair(pub(crate) f64, pub(crate) f64);

impl<'a, 'py> FromPyObject<'a, 'py> for FloatPair {
    type Error = PyErr;

    fn extract(ob: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let two = items(&ob, "two numbers (lo, hi)")?;
        let number = |x: &Bound<'_, PyAny>| {
            x.extract::<f64>().map_err(|_| {
                bad_input(format!(
                    "expected a number, got {}",
                    x.repr().map_or_else(|_| "?".into(), |r| r.to_string())
                ))
            })
        };
        match two.as_slice() {
            [lo, hi] => Ok(FloatPair(number(lo)?, number(hi)?)),
            _ => Err(bad_input(format!(
                "expected two numbers (lo, hi), got {} values",
                two.len()
            ))),
        }
    }
}

/// Integers in a sequence or a numpy array of any integer, bool or whole float dtype
/// (range checks are the caller's, with the field's name).
pub(crate) struct Integers(pub(crate) Vec<i64>);

impl<'a, 'py> FromPyObject<'a, 'py> for Integers {
    type Error = PyErr;

    fn extract(ob: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        items(&ob, "a sequence of whole numbers")?
            .iter()
            .map(|x| {
                integer(x).and_then(|v| {
                    i64::try_from(v).map_err(|_| bad_input(format!("{v} is out of range")))
                })
            })
            .collect::<PyResult<Vec<i64>>>()
            .map(Integers)
    }
}

/// Rows of integers: a list of lists or a 2-D numpy array, as [`Integers`] reads each row.
pub(crate) struct IntegerRows(pub(crate) Vec<Vec<i64>>);

impl<'a, 'py> FromPyObject<'a, 'py> for IntegerRows {
    type Error = PyErr;

    fn extract(ob: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        items(&ob, "rows of whole numbers")?
            .iter()
            .map(|row| row.extract::<Integers>().map(|r| r.0))
            .collect::<PyResult<Vec<Vec<i64>>>>()
            .map(IntegerRows)
    }
}
