//! The built-in methods by their command-line names, and the one door through which
//! a user's limits become an allocator.

use afg_game::Preference;
use serde::{Deserialize, Serialize};

use crate::{
    AllocError, Allocator, Blind, CentralisedDa, DecentralisedDa, Greedy, Nearest, Optimum,
    RandomAllocator, TeamOptimum,
};

/// The built-in methods, by command-line name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// [`Optimum`].
    Opt,
    /// GRAPE DA, centralised twin ([`CentralisedDa`], selfish).
    Da,
    /// GRAPE DA, decentralised ([`DecentralisedDa`], selfish).
    DaDecentralised,
    /// Balanced DA ([`CentralisedDa`], balanced).
    DaBalanced,
    /// [`Greedy`].
    Greedy,
    /// [`Nearest`].
    Nearest,
    /// [`RandomAllocator`].
    Random,
    /// [`Blind`].
    Blind,
}

impl Method {
    /// Every method, OPT first.
    pub const ALL: [Method; 8] = [
        Method::Opt,
        Method::Da,
        Method::DaDecentralised,
        Method::DaBalanced,
        Method::Greedy,
        Method::Nearest,
        Method::Random,
        Method::Blind,
    ];

    /// The centralised methods, OPT first: those a training log compares against.
    pub const CENTRALISED: [Method; 6] = [
        Method::Opt,
        Method::Da,
        Method::DaBalanced,
        Method::Greedy,
        Method::Nearest,
        Method::Random,
    ];

    /// The allocator; `seed` is used by the randomised methods.
    pub fn allocator(self, seed: u64) -> Box<dyn Allocator> {
        match self {
            Method::Opt => Box::new(Optimum),
            Method::Da => Box::new(CentralisedDa::new(Preference::Selfish)),
            Method::DaDecentralised => Box::new(DecentralisedDa::new(Preference::Selfish, seed)),
            Method::DaBalanced => Box::new(CentralisedDa::new(Preference::Balanced)),
            Method::Greedy => Box::new(Greedy),
            Method::Nearest => Box::new(Nearest),
            Method::Random => Box::new(RandomAllocator { seed }),
            Method::Blind => Box::new(Blind),
        }
    }

    /// The allocator, with `exact`'s limits (time, gap, stop, progress: see
    /// [`TeamOptimum::stopping`]) where they are given: the one place a user's limits
    /// become a solver (the command line, Python, missions and the benchmarks all come
    /// here). Only the exact optimum takes them.
    ///
    /// # Errors
    /// [`AllocError::InvalidParameter`] where limits are given to another method.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::{Method, TeamOptimum};
    /// let limited = TeamOptimum::with_time_limit(2.5)?;
    /// assert_eq!(Method::Opt.allocator_with(0, Some(limited.clone()))?.name(), "opt");
    /// assert!(Method::Greedy.allocator_with(0, Some(limited)).is_err());
    /// assert_eq!(Method::Greedy.allocator_with(0, None)?.name(), "greedy");
    /// # Ok::<(), afg_baseline::AllocError>(())
    /// ```
    pub fn allocator_with(
        self,
        seed: u64,
        exact: Option<TeamOptimum>,
    ) -> Result<Box<dyn Allocator>, AllocError> {
        match exact {
            None => Ok(self.allocator(seed)),
            Some(exact) if self == Method::Opt => Ok(Box::new(exact)),
            Some(_) => Err(AllocError::InvalidParameter(
                "a time limit or a gap is for the exact optimum (method opt) only".into(),
            )),
        }
    }

    /// The exact solver this method runs with a user's `time_limit` and `gap` (see
    /// [`TeamOptimum::limits`]): for `opt` always one, limited or not, so that a front
    /// end can set its stop flag and progress hook; for another method the limits
    /// alone, which [`Method::allocator_with`] refuses. The same answers as
    /// [`Method::allocator`] where no limit is given: `opt` plays the paper's game as
    /// [`Optimum`] and a team game as [`TeamOptimum`] either way.
    ///
    /// # Errors
    /// As [`TeamOptimum::stopping`].
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::Method;
    /// assert!(Method::Opt.exact(None, None)?.is_some());
    /// assert!(Method::Greedy.exact(None, None)?.is_none());
    /// assert!(Method::Greedy.exact(Some(1.0), None)?.is_some()); // refused by allocator_with
    /// # Ok::<(), afg_baseline::AllocError>(())
    /// ```
    pub fn exact(
        self,
        time_limit: Option<f64>,
        gap: Option<f64>,
    ) -> Result<Option<TeamOptimum>, AllocError> {
        let limits = TeamOptimum::limits(time_limit, gap)?;
        Ok(limits.or_else(|| (self == Method::Opt).then(TeamOptimum::default)))
    }

    /// The label of tables and figures.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::Method;
    /// assert_eq!(Method::Da.label(), "GRAPE DA");
    /// assert_eq!("da".parse::<Method>().unwrap().label(), "GRAPE DA");
    /// ```
    pub fn label(self) -> &'static str {
        match self {
            Method::Opt => "OPT",
            Method::Da => "GRAPE DA",
            Method::DaDecentralised => "GRAPE DA, decentralised",
            Method::DaBalanced => "balanced DA",
            Method::Greedy => "Greedy",
            Method::Nearest => "Nearest",
            Method::Random => "Random",
            Method::Blind => "Blind round robin",
        }
    }

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Opt => "opt",
            Method::Da => "da",
            Method::DaDecentralised => "da-decentralised",
            Method::DaBalanced => "da-balanced",
            Method::Greedy => "greedy",
            Method::Nearest => "nearest",
            Method::Random => "random",
            Method::Blind => "blind",
        }
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Method::ALL.iter().map(|m| m.name()).collect();
                format!("unknown method '{s}'; expected one of {}", names.join(", "))
            })
    }
}
