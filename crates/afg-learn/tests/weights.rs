//! Weight files: round trips, and bad or out-of-range files refused with clear errors.

mod common;

use std::path::PathBuf;

use afg_baseline::Allocator;
use afg_game::GeneratorConfig;
use afg_learn::{
    InferBackend, LearnError,
    nets::{NetworkConfig, load_network, save_network},
    policy::LearnedPolicy,
};
use burn::module::{Module, ModuleMapper, Param};
use burn::tensor::Tensor;

use common::{configs, price_headed};

type B = InferBackend;

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("afg-learn-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn weights_round_trip_and_drive_the_same_policy() {
    let dir = temp_dir("roundtrip");
    let inst = GeneratorConfig::paper(40, 5, 6).generate().unwrap();
    for config in configs() {
        let stem = dir.join(config.name());
        let policy = LearnedPolicy::new(config.clone());
        save_network(config.init::<B>(&Default::default()), &config, &stem).unwrap();
        let loaded = LearnedPolicy::load(&stem).unwrap();
        assert_eq!(loaded.config(), &config);
        assert_eq!(
            policy.allocate(&inst).unwrap().assignment,
            loaded.allocate(&inst).unwrap().assignment
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Makes every weight NaN.
struct Poison;
impl<Bk: burn::tensor::backend::Backend> ModuleMapper<Bk> for Poison {
    fn map_float<const D: usize>(&mut self, param: Param<Tensor<Bk, D>>) -> Param<Tensor<Bk, D>> {
        param.map(|t| t.mul_scalar(f32::NAN))
    }
}

#[test]
fn bad_weight_files_are_clear_errors() {
    let dir = temp_dir("bad");
    let config = NetworkConfig::afgnet(5, 1);
    let stem = dir.join("net");
    save_network(config.init::<B>(&Default::default()), &config, &stem).unwrap();
    let mpk = dir.join("net.mpk");
    let json = dir.join("net.json");

    // Weights of another shape: an S2V record under an AFGNet header.
    let other = dir.join("other");
    let s2v = NetworkConfig::s2v(5, 1);
    save_network(s2v.init::<B>(&Default::default()), &s2v, &other).unwrap();
    std::fs::copy(dir.join("other.json"), &json).unwrap();
    let err = load_network::<B>(&stem, &Default::default()).unwrap_err();
    assert!(matches!(err, LearnError::Weights { .. }), "{err}");

    // A NaN weight: the file reads, but the network would compute nothing meaningful.
    let poisoned = config.init::<B>(&Default::default()).map(&mut Poison);
    save_network(poisoned, &config, &stem).unwrap();
    let err = load_network::<B>(&stem, &Default::default()).unwrap_err();
    assert!(err.to_string().contains("NaN or infinite weight"), "{err}");

    // Another width: d = 32 header over d = 64 weights.
    save_network(config.init::<B>(&Default::default()), &config, &stem).unwrap();
    let text = std::fs::read_to_string(&json)
        .unwrap()
        .replace("\"hidden\": 64", "\"hidden\": 32");
    std::fs::write(&json, text).unwrap();
    let err = load_network::<B>(&stem, &Default::default()).unwrap_err();
    assert!(err.to_string().contains("shapes differ"), "{err}");

    // A price-headed record under a header without the head (and the reverse).
    let headed = price_headed(1);
    save_network(headed.init::<B>(&Default::default()), &headed, &stem).unwrap();
    let text = std::fs::read_to_string(&json).unwrap();
    let plain = text.replace("\"price_head\": true", "\"price_head\": false");
    assert_ne!(plain, text);
    std::fs::write(&json, plain).unwrap();
    let err = load_network::<B>(&stem, &Default::default()).unwrap_err();
    assert!(err.to_string().contains("price head"), "{err}");
    save_network(config.init::<B>(&Default::default()), &config, &stem).unwrap();
    std::fs::write(&json, text).unwrap();
    let err = load_network::<B>(&stem, &Default::default()).unwrap_err();
    assert!(matches!(err, LearnError::Weights { .. }), "{err}");

    // A truncated record.
    save_network(config.init::<B>(&Default::default()), &config, &stem).unwrap();
    let bytes = std::fs::read(&mpk).unwrap();
    std::fs::write(&mpk, &bytes[..bytes.len() / 2]).unwrap();
    let err = load_network::<B>(&stem, &Default::default()).unwrap_err();
    assert!(err.to_string().contains("corrupt or truncated"), "{err}");

    // A header of a later version, one of format 1 (named as such), and one that is
    // not JSON.
    std::fs::write(
        &json,
        "{\"format\":\"afg-weights\",\"version\":7,\"network\":{\"net\":\"s2v\",\"tasks\":5}}",
    )
    .unwrap();
    assert!(load_network::<B>(&stem, &Default::default()).is_err());
    std::fs::write(
        &json,
        "{\"format\":\"afg-weights\",\"version\":1,\"network\":{\"net\":\"s2v\",\"tasks\":5}}",
    )
    .unwrap();
    let err = load_network::<B>(&stem, &Default::default()).unwrap_err();
    assert!(err.to_string().contains("afg migrate"), "{err}");
    std::fs::write(&json, "garbage").unwrap();
    assert!(
        load_network::<B>(&stem, &Default::default())
            .unwrap_err()
            .to_string()
            .contains("not a weights header")
    );

    // A network for another M refuses the instance.
    let inst = GeneratorConfig::paper(10, 3, 1).generate().unwrap();
    assert!(
        LearnedPolicy::new(NetworkConfig::afgnet(5, 0))
            .allocate(&inst)
            .is_err()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Sizes out of range are refused before anything is built, and unknown fields too.
#[test]
fn out_of_range_headers_are_clear_errors() {
    let dir = temp_dir("sizes");
    let config = NetworkConfig::afgnet(5, 1);
    let stem = dir.join("net");
    let json = dir.join("net.json");
    save_network(config.init::<B>(&Default::default()), &config, &stem).unwrap();
    let text = std::fs::read_to_string(&json).unwrap();
    for (from, to, says) in [
        ("\"hidden\": 64", "\"hidden\": 0", "hidden is 0"),
        ("\"tasks\": 5", "\"tasks\": 0", "tasks is 0"),
        (
            "\"layers\": 3",
            "\"layers\": 100000000",
            "layers is 100000000",
        ),
        (
            "\"hidden\": 64",
            "\"hidden\": 4000000000",
            "hidden is 4000000000",
        ),
        ("\"hidden\": 64", "\"hidden\": 64, \"hiden\": 3", "hiden"),
    ] {
        assert!(text.contains(from), "{from}");
        std::fs::write(&json, text.replace(from, to)).unwrap();
        let err = load_network::<B>(&stem, &Default::default()).unwrap_err();
        assert!(err.to_string().contains(says), "{err}");
    }
}
