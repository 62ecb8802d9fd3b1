//! The numbers the paper reports, to print beside ours.

use afg_learn::{nets::Net, train::Algo};

use crate::ModelSpec;

/// One scale of the paper's Table I.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Table1Row {
    /// Robots N.
    pub robots: usize,
    /// Mean welfare of S2V_DDQN.
    pub s2v_ddqn: f64,
    /// Mean welfare of AFGNet_DQN.
    pub afgnet_dqn: f64,
    /// Mean welfare of AFGNet_DDQN.
    pub afgnet_ddqn: f64,
    /// NS_rate of AFGNet_DDQN, in percent.
    pub afgnet_ddqn_ns_rate: f64,
}

impl Table1Row {
    /// The paper's welfare for `model`, if it reports one (not for ours, nor for a warm
    /// start).
    ///
    /// # Examples
    /// ```
    /// use xtask::{ModelSpec, paper};
    /// let row = paper::table1(60).unwrap();
    /// assert_eq!(row.welfare_of(&ModelSpec::afgnet_ddqn(60)), Some(59.51));
    /// ```
    pub fn welfare_of(&self, model: &ModelSpec) -> Option<f64> {
        if !model.is_paper_method() {
            return None;
        }
        match (model.net, model.algo) {
            (Net::S2v, Algo::Ddqn) => Some(self.s2v_ddqn),
            (Net::AfgNet, Algo::Dqn) => Some(self.afgnet_dqn),
            (Net::AfgNet, Algo::Ddqn) => Some(self.afgnet_ddqn),
            _ => None,
        }
    }
}

/// The paper's Table I.
pub const TABLE1: [Table1Row; 3] = [
    Table1Row {
        robots: 20,
        s2v_ddqn: 14.85,
        afgnet_dqn: 19.31,
        afgnet_ddqn: 22.61,
        afgnet_ddqn_ns_rate: 81.8,
    },
    Table1Row {
        robots: 60,
        s2v_ddqn: 42.37,
        afgnet_dqn: 48.00,
        afgnet_ddqn: 59.51,
        afgnet_ddqn_ns_rate: 80.8,
    },
    Table1Row {
        robots: 100,
        s2v_ddqn: 96.18,
        afgnet_dqn: 96.99,
        afgnet_ddqn: 106.21,
        afgnet_ddqn_ns_rate: 78.0,
    },
];

/// One scale of the paper's Table II (DA against AFGNet DDQN trained at N = 60).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Table2Row {
    /// Robots N.
    pub robots: usize,
    /// Mean welfare of GRAPE DA.
    pub da_welfare: f64,
    /// Mean welfare of the model trained at N = 60 ("Pretrain_60").
    pub pretrain60_welfare: f64,
    /// NS_rate of DA, in percent.
    pub da_ns_rate: f64,
    /// NS_rate of Pretrain_60, in percent.
    pub pretrain60_ns_rate: f64,
    /// Seconds per instance of DA (MATLAB).
    pub da_seconds: f64,
    /// Seconds per instance of Pretrain_60.
    pub pretrain60_seconds: f64,
}

/// The paper's Table II.
pub const TABLE2: [Table2Row; 2] = [
    Table2Row {
        robots: 500,
        da_welfare: 619.11,
        pretrain60_welfare: 620.23,
        da_ns_rate: 80.5,
        pretrain60_ns_rate: 79.5,
        da_seconds: 181.83,
        pretrain60_seconds: 2.66,
    },
    Table2Row {
        robots: 1000,
        da_welfare: 1247.53,
        pretrain60_welfare: 1250.75,
        da_ns_rate: 80.0,
        pretrain60_ns_rate: 81.1,
        da_seconds: 714.88,
        pretrain60_seconds: 10.42,
    },
];

/// The paper's Table I row for N = `robots`.
pub fn table1(robots: usize) -> Option<&'static Table1Row> {
    TABLE1.iter().find(|r| r.robots == robots)
}

/// The paper's Table II row for N = `robots`.
pub fn table2(robots: usize) -> Option<&'static Table2Row> {
    TABLE2.iter().find(|r| r.robots == robots)
}
