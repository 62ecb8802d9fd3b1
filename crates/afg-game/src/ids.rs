//! Typed indices for robots and tasks, so the two are never confused.

use serde::{Deserialize, Serialize};

macro_rules! id_type {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
        #[serde(transparent)]
        pub struct $name(pub u32);

        impl $name {
            /// The index as a `usize`, for indexing slices.
            #[inline]
            pub fn index(self) -> usize {
                self.0 as usize
            }
        }

        impl From<usize> for $name {
            #[inline]
            fn from(i: usize) -> Self {
                $name(u32::try_from(i).expect("index exceeds u32::MAX"))
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "{}", self.0)
            }
        }
    };
}

id_type!(
    /// Index of a robot in an [`Instance`](crate::Instance), `0..N`.
    ///
    /// # Examples
    /// ```
    /// use afg_game::RobotId;
    /// assert_eq!(RobotId::from(3).index(), 3);
    /// ```
    RobotId
);
id_type!(
    /// Index of a task in an [`Instance`](crate::Instance), `0..M`.
    ///
    /// # Examples
    /// ```
    /// use afg_game::TaskId;
    /// assert_eq!(TaskId(2).to_string(), "2");
    /// ```
    TaskId
);
