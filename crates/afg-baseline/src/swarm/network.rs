//! The network model: who can hear whom, which messages are lost or late, when robots
//! wake, and which robots stop.

use afg_graph::GraphKind;
use serde::{Deserialize, Serialize};

use crate::AllocError;

/// The network a decentralised method talks over. [`Network::default`] is the
/// perfect one of GRAPE's analysis: kNN links (k = 10), every message delivered in
/// the round it is sent, every robot awake every round, none failing.
///
/// # Examples
/// ```
/// use afg_baseline::{Failure, Network};
/// use afg_graph::GraphKind;
/// let lossy = Network {
///     graph: GraphKind::Radius { radius: 1.5 },
///     loss: 0.3,
///     burst: Some(4.0),
///     failure: Some(Failure::new(0.1, 20)),
///     ..Network::default()
/// };
/// assert!(lossy.check().is_ok());
/// assert!(Network { loss: 1.0, ..Network::default() }.check().is_err());
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Network {
    /// Who can hear whom (a disk radius, or the k nearest). If the graph is
    /// disconnected, each stray component is linked to its nearest robot outside it.
    pub graph: GraphKind,
    /// The long-run share of messages lost, in [0, 1).
    pub loss: f64,
    /// Mean length in rounds of a run of losses on one link (Gilbert–Elliott: a link
    /// is good or bad, bad links lose every message); `None` for independent losses.
    pub burst: Option<f64>,
    /// A delivered message arrives a uniform 0..=`max_delay` rounds after it is sent.
    pub max_delay: u32,
    /// The chance that a robot wakes in a round (1 = synchronous rounds). An asleep
    /// robot neither moves nor sends; it still receives.
    pub activation: f64,
    /// Robots that stop mid-run.
    pub failure: Option<Failure>,
    /// Links that cross the vertical line through the robots' median x are down until
    /// this round: the swarm works in two halves, then they merge.
    pub partition_until: Option<u64>,
}

/// Robots that crash: `fraction` of the robots alive stop at the start of round
/// `at_round` (chosen at random) and never send again. Their neighbours notice after
/// `detect_after` silent rounds (a robot with no living neighbour is noticed by its
/// nearest living robot) and remove it from the partition; the survivors relink to
/// their own nearest (the same graph rule over the survivors).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Failure {
    /// Share of the robots that crash, in [0, 1).
    pub fraction: f64,
    /// The round they crash at (from 1).
    pub at_round: u64,
    /// Silent rounds before a neighbour removes a crashed robot (at least 1).
    pub detect_after: u64,
}

impl Failure {
    /// `fraction` of the robots crash at `at_round`, noticed after 3 silent rounds.
    pub fn new(fraction: f64, at_round: u64) -> Self {
        Failure {
            fraction,
            at_round,
            detect_after: 3,
        }
    }
}

impl Default for Network {
    fn default() -> Self {
        Network {
            graph: GraphKind::default(),
            loss: 0.0,
            burst: None,
            max_delay: 0,
            activation: 1.0,
            failure: None,
            partition_until: None,
        }
    }
}

impl Network {
    /// Checks every knob's range, and that a burst length can give the loss.
    ///
    /// # Errors
    /// [`AllocError::InvalidParameter`] saying which value is out of range.
    pub fn check(&self) -> Result<(), AllocError> {
        let bad = |what: String| Err(AllocError::InvalidParameter(what));
        if !(0.0..1.0).contains(&self.loss) {
            return bad(format!("loss {} must be in [0, 1)", self.loss));
        }
        if !(self.activation > 0.0 && self.activation <= 1.0) {
            return bad(format!("activation {} must be in (0, 1]", self.activation));
        }
        if let Some(burst) = self.burst {
            if !(burst.is_finite() && burst >= 1.0) {
                return bad(format!("burst length {burst} must be at least 1 round"));
            }
            if gilbert_elliott(self.loss, burst).0 > 1.0 {
                return bad(format!(
                    "bursts of mean length {burst} cannot lose {} of the messages: at most {:.3}",
                    self.loss,
                    burst / (burst + 1.0)
                ));
            }
        }
        if let Some(f) = self.failure {
            if !(0.0..1.0).contains(&f.fraction) {
                return bad(format!("failing share {} must be in [0, 1)", f.fraction));
            }
            if f.at_round == 0 || f.detect_after == 0 {
                return bad("failures start at round 1 or later and take a round to notice".into());
            }
        }
        Ok(())
    }

    /// Whether this is GRAPE's perfect network (any graph).
    pub fn is_perfect(&self) -> bool {
        self.loss == 0.0
            && self.max_delay == 0
            && self.activation == 1.0
            && self.failure.is_none()
            && self.partition_until.is_none()
    }
}

/// Gilbert–Elliott transition chances (good → bad, bad → good) for a long-run loss
/// `loss` and a mean bad run of `burst` rounds.
pub(super) fn gilbert_elliott(loss: f64, burst: f64) -> (f64, f64) {
    let to_good = 1.0 / burst;
    (loss * to_good / (1.0 - loss), to_good)
}
