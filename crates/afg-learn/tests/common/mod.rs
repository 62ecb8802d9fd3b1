//! Networks the model and weight-file tests share.

use afg_learn::nets::{AfgNetConfig, NetworkConfig};

/// AFGNet with a price head, in bounded units.
pub fn price_headed(seed: u64) -> NetworkConfig {
    NetworkConfig::AfgNet(
        AfgNetConfig::new(5, afg_graph::Units::MeanReward)
            .with_price_head(true)
            .with_seed(seed),
    )
    .with_units(afg_graph::Units::Bounded)
}

/// One network of each kind: AFGNet, S2V, AFGNet with a price head.
pub fn configs() -> [NetworkConfig; 3] {
    [
        NetworkConfig::afgnet(5, 3),
        NetworkConfig::s2v(5, 3),
        price_headed(3),
    ]
}
