//! How a run decides and what it checks: the replanning rule, the decision latency and
//! the options besides the allocator.

use afg_baseline::Allocator;
use afg_game::Preference;
use serde::Serialize;

use super::Decentralised;
use crate::MissionError;

/// How each decision is made.
#[derive(Clone, Copy)]
pub enum Replan<'a> {
    /// The allocator, from scratch, at every decision.
    Scratch(&'a dyn Allocator),
    /// The allocator at the first decision; after it, survivors keep their task (if it
    /// is still open) and best-response dynamics under `preference` settle the rest.
    Warm {
        /// The first decision's allocator.
        first: &'a dyn Allocator,
        /// The dynamics' preference.
        preference: Preference,
    },
    /// The exact optimum, re-solved at every decision from the previous decision's task
    /// prices (a new task starts at [`Optimum::start_price`](afg_baseline::Optimum::start_price)):
    /// the same optimum, found from a warm start.
    WarmOpt,
    /// No central decision: the robots run a decentralised method round by round and
    /// each heads where its own view says.
    Decentralised(&'a Decentralised),
}

/// How long a decision takes in mission time: robots act on it only once it is made.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum Latency {
    /// Decisions take no mission time.
    None,
    /// Each decision takes this many time units.
    Fixed {
        /// Time units per decision.
        delay: f64,
    },
    /// Each decision takes the allocator's measured compute time times `factor`
    /// (mission time units per second of compute): not reproducible run to run.
    Measured {
        /// Mission time units per second.
        factor: f64,
    },
}

impl Latency {
    /// The latency the front ends' two knobs give: `delay` time units per decision, or
    /// `factor` mission time units per second of compute, or none.
    ///
    /// # Errors
    /// [`MissionError::Invalid`] when both are given.
    ///
    /// # Examples
    /// ```
    /// use afg_mission::Latency;
    /// assert_eq!(Latency::from_knobs(Some(0.5), None)?, Latency::Fixed { delay: 0.5 });
    /// assert_eq!(Latency::from_knobs(None, None)?, Latency::None);
    /// assert!(Latency::from_knobs(Some(0.5), Some(2.0)).is_err());
    /// # Ok::<(), afg_mission::MissionError>(())
    /// ```
    pub fn from_knobs(delay: Option<f64>, factor: Option<f64>) -> Result<Latency, MissionError> {
        match (delay, factor) {
            (Some(_), Some(_)) => Err(MissionError::Invalid(
                "give a fixed latency or a latency factor, not both".into(),
            )),
            (Some(delay), None) => Ok(Latency::Fixed { delay }),
            (None, Some(factor)) => Ok(Latency::Measured { factor }),
            (None, None) => Ok(Latency::None),
        }
    }
}

/// The options of a run besides the allocator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunOptions {
    /// Also decide every this many time units, not only at events.
    pub replan_every: Option<f64>,
    /// How long decisions take.
    pub latency: Latency,
    /// Keep every event and decision ([`MissionRun::trace`](crate::MissionRun::trace)).
    pub trace: bool,
    /// Snapshot the whole state every this many time units ([`MissionRun::frames`](crate::MissionRun::frames):
    /// the animation's frames).
    pub frame_every: Option<f64>,
    /// Commitment: robots at work stay until their task is done.
    pub commit: bool,
    /// Hysteresis: a travelling robot switches task only for a gain (in balanced
    /// score, the decision's game) above this.
    pub hysteresis: Option<f64>,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            frame_every: None,
            commit: false,
            hysteresis: None,
            replan_every: None,
            latency: Latency::None,
            trace: false,
        }
    }
}

/// A time between frames that is finite and positive, or none.
pub(crate) fn check_frame_every(frame_every: Option<f64>) -> Result<(), MissionError> {
    if frame_every.is_some_and(|every| !(every.is_finite() && every > 0.0)) {
        return Err(MissionError::Invalid(
            "the time between frames must be finite and positive".into(),
        ));
    }
    Ok(())
}

/// Every option in range.
pub(crate) fn check_options(options: &RunOptions) -> Result<(), MissionError> {
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if options.replan_every.is_some_and(|r| !positive(r)) {
        return Err(MissionError::Invalid(
            "the replanning interval must be finite and positive".into(),
        ));
    }
    if options.hysteresis.is_some_and(|h| h.is_nan() || h < 0.0) {
        return Err(MissionError::Invalid(
            "the hysteresis threshold must be ≥ 0".into(),
        ));
    }
    check_frame_every(options.frame_every)?;
    let latency_ok = match options.latency {
        Latency::None => true,
        Latency::Fixed { delay } => delay.is_finite() && delay >= 0.0,
        Latency::Measured { factor } => factor.is_finite() && factor >= 0.0,
    };
    if !latency_ok {
        return Err(MissionError::Invalid(
            "the decision latency must be finite and ≥ 0".into(),
        ));
    }
    Ok(())
}
