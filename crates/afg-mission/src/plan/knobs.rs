//! The knobs of the methods run by the robots over the radio (`grape`, `auction`), as
//! every front end spells them, with their one set of defaults.

use afg_baseline::Network;
use afg_game::Preference;
use afg_graph::GraphKind;

use crate::MissionMethod;

/// The radio's knobs as the front ends spell them (`--radius`, `--knn`, `--loss`,
/// `--burst`, `--delay`, `--activation`); [`RadioKnobs::network`] is the [`Network`] they
/// give. The defaults are [`Network::default`]'s: each robot linked to its 10 nearest,
/// no loss, no delay, synchronous rounds.
///
/// # Examples
/// ```
/// use afg_graph::GraphKind;
/// use afg_mission::RadioKnobs;
/// let radio = RadioKnobs { radius: Some(0.2), loss: 0.3, ..RadioKnobs::default() };
/// let network = radio.network();
/// assert_eq!(network.graph, GraphKind::Radius { radius: 0.2 });
/// assert_eq!(network.loss, 0.3);
/// assert_eq!(RadioKnobs::default().network().graph, GraphKind::Knn { k: 10 });
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadioKnobs {
    /// Link robots within this distance instead of to their nearest.
    pub radius: Option<f64>,
    /// Link each robot to its K nearest (kept in both directions), unless `radius`.
    pub knn: usize,
    /// The long-run share of messages lost, in [0, 1).
    pub loss: f64,
    /// Losses come in bursts of this mean length in rounds (Gilbert–Elliott) instead
    /// of independently.
    pub burst: Option<f64>,
    /// A delivered message arrives 0..=`delay` rounds late (uniform).
    pub delay: u32,
    /// Asynchronous robots: each wakes in a round with this chance (1 = synchronous).
    pub activation: f64,
}

impl Default for RadioKnobs {
    fn default() -> Self {
        let network = Network::default();
        let GraphKind::Knn { k } = GraphKind::default() else {
            unreachable!("robots link to their nearest by default")
        };
        RadioKnobs {
            radius: None,
            knn: k,
            loss: network.loss,
            burst: network.burst,
            delay: network.max_delay,
            activation: network.activation,
        }
    }
}

impl RadioKnobs {
    /// The network of these knobs (a radius wins over `knn`), with no failures or
    /// partition of its own.
    pub fn network(&self) -> Network {
        let graph = match self.radius {
            Some(radius) => GraphKind::Radius { radius },
            None => GraphKind::Knn { k: self.knn },
        };
        Network {
            graph,
            loss: self.loss,
            burst: self.burst,
            max_delay: self.delay,
            activation: self.activation,
            ..Network::default()
        }
    }

    /// The knobs set away from their defaults, by their command-line names.
    fn changed(&self) -> Vec<&'static str> {
        let default = RadioKnobs::default();
        [
            (self.radius != default.radius, "radius"),
            (self.knn != default.knn, "knn"),
            (self.loss != default.loss, "loss"),
            (self.burst != default.burst, "burst"),
            (self.delay != default.delay, "delay"),
            (self.activation != default.activation, "activation"),
        ]
        .into_iter()
        .filter_map(|(changed, name)| changed.then_some(name))
        .collect()
    }
}

/// The knobs of a decentralised method run by the robots over the radio, with the one
/// set of defaults every front end shows: GRAPE selfish (its own rule), the auction's
/// ε = 10⁻³, the radio of [`RadioKnobs::default`], 100 rounds per time unit, every task
/// heard of at once.
///
/// # Examples
/// ```
/// use afg_game::Preference;
/// use afg_mission::SwarmKnobs;
/// let knobs = SwarmKnobs::default();
/// assert_eq!((knobs.preference, knobs.epsilon, knobs.rounds_per_time), (Preference::Selfish, 1e-3, 100.0));
/// assert!(knobs.sensing.is_none() && knobs.radio.loss == 0.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SwarmKnobs {
    /// GRAPE's preference: selfish (GRAPE's own) or balanced.
    pub preference: Preference,
    /// The auction's least price increment ε.
    pub epsilon: f64,
    /// The radio: who hears whom (re-evaluated every round as robots move), losses,
    /// bursts, delays, asynchrony.
    pub radio: RadioKnobs,
    /// Rounds per mission time unit.
    pub rounds_per_time: f64,
    /// Robots see tasks within this distance and hear of the others from their
    /// neighbours (`None`: every robot hears of every task at once).
    pub sensing: Option<f64>,
}

impl Default for SwarmKnobs {
    fn default() -> Self {
        SwarmKnobs {
            preference: Preference::Selfish,
            epsilon: 1e-3,
            radio: RadioKnobs::default(),
            rounds_per_time: 100.0,
            sensing: None,
        }
    }
}

impl SwarmKnobs {
    /// The ε where none is given, for `method` on games of which some task `needs_teams`
    /// (a threshold or a skill; [`crate::Mission::needs_teams`], [`afg_game::Instance::has_teams`]):
    /// for the auction, 0.01 where a task needs a team or a skill; the default 0.001
    /// otherwise (a method that does not use ε refuses any other). At 0.001 the
    /// auction's robots beyond the teams bid the places left up in steps too small to
    /// settle before a team mission's horizon (docs/teams.md measures it). The one rule
    /// for `afg mission`, `afg swarm` and Python alike.
    ///
    /// # Examples
    /// ```
    /// use afg_mission::{MissionConfig, MissionMethod, Preset, SwarmKnobs};
    /// let mut config = MissionConfig::new(Preset::Static, 8, 2, 1);
    /// let plain = config.generate()?;
    /// config.min_team = Some(afg_game::CountRange { min: 2, max: 3 });
    /// let teams = config.generate()?;
    /// let auction = MissionMethod::Auction;
    /// assert_eq!(SwarmKnobs::default_epsilon(auction, plain.needs_teams()), 1e-3);
    /// assert_eq!(SwarmKnobs::default_epsilon(auction, teams.needs_teams()), 0.01);
    /// assert_eq!(SwarmKnobs::default_epsilon(MissionMethod::Grape, true), 1e-3);
    /// # Ok::<(), afg_mission::MissionError>(())
    /// ```
    pub fn default_epsilon(method: MissionMethod, needs_teams: bool) -> f64 {
        if method == MissionMethod::Auction && needs_teams {
            Self::TEAM_EPSILON
        } else {
            Self::default().epsilon
        }
    }

    /// The auction's ε on missions whose tasks need teams or skills.
    pub const TEAM_EPSILON: f64 = 0.01;

    /// The knobs set away from their defaults, by their command-line names.
    pub(super) fn changed(&self) -> Vec<&'static str> {
        let default = SwarmKnobs::default();
        let mut changed: Vec<&'static str> = [
            (self.preference != default.preference, "preference"),
            (self.epsilon != default.epsilon, "epsilon"),
            (
                self.rounds_per_time != default.rounds_per_time,
                "rounds-per-time",
            ),
            (self.sensing != default.sensing, "sensing"),
        ]
        .into_iter()
        .filter_map(|(changed, name)| changed.then_some(name))
        .collect();
        changed.extend(self.radio.changed());
        changed
    }
}
