//! Weight files of a Q network.
//!
//! Weights are stored as two files with one stem: `STEM.json`, a header
//! (`{"format": "afg-weights", "version": 2, "network": {..config..}}`), and
//! `STEM.mpk`, Burn's named MessagePack record in full precision. Loading checks the
//! header and then every parameter's shape against the configured network.

use std::path::{Path, PathBuf};

use burn::module::{Module, ModuleVisitor, Param};
use burn::record::{
    FullPrecisionSettings, NamedMpkBytesRecorder, NamedMpkFileRecorder, Record, Recorder,
};
use burn::tensor::Tensor;
use burn::tensor::backend::Backend;
use serde::{Deserialize, Serialize};

use crate::LearnError;
use crate::qnetwork::QNetworkRecord;
use crate::qnetwork::{NetworkConfig, QNetwork};

fn weights_error(path: &Path, reason: impl Into<String>) -> LearnError {
    LearnError::Weights {
        path: path.display().to_string(),
        reason: reason.into(),
    }
}

const WEIGHTS_FORMAT: &str = "afg-weights";
/// Format 2: the network configuration states every field ([`crate::run::migrate_run`]).
const WEIGHTS_VERSION: u32 = crate::format::RUN_FORMAT_VERSION;

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct WeightsHeader {
    format: String,
    version: u32,
    network: NetworkConfig,
}

fn with_extension(stem: &Path, ext: &str) -> PathBuf {
    let mut s = stem.as_os_str().to_owned();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}

/// Writes a Burn record to `path` as named MessagePack in full precision (the format
/// of Burn's `NamedMpkFileRecorder`), atomically and durably
/// ([`afg_game::fs::write_atomic`]).
///
/// # Errors
/// [`LearnError::Weights`] if the record cannot be encoded or the file written.
pub(crate) fn write_record<B: Backend, R: Record<B>>(
    record: R,
    path: &Path,
) -> Result<(), LearnError> {
    let bytes = Recorder::<B>::record(
        &NamedMpkBytesRecorder::<FullPrecisionSettings>::new(),
        record,
        (),
    )
    .map_err(|e| weights_error(path, e.to_string()))?;
    afg_game::fs::write_atomic(path, &bytes).map_err(|e| weights_error(path, e.to_string()))
}

/// Saves `network` (built from `config`) as `stem.mpk` + `stem.json`, each written
/// atomically and durably, so existing weights are never half-overwritten.
///
/// # Errors
/// [`LearnError::Weights`] if a file cannot be written.
pub fn save_network<B: Backend>(
    network: QNetwork<B>,
    config: &NetworkConfig,
    stem: &Path,
) -> Result<(), LearnError> {
    write_record::<B, _>(network.into_record(), &with_extension(stem, "mpk"))?;
    let json = header_json(config);
    afg_game::fs::write_atomic(&with_extension(stem, "json"), json.as_bytes())?;
    Ok(())
}

/// The weights header of a network configured by `config`, as written.
pub(crate) fn header_json(config: &NetworkConfig) -> String {
    let header = WeightsHeader {
        format: WEIGHTS_FORMAT.into(),
        version: WEIGHTS_VERSION,
        network: config.clone(),
    };
    serde_json::to_string_pretty(&header).expect("a header always serialises")
}

/// Collects parameter shapes in visiting order.
struct Shapes(Vec<Vec<usize>>);

impl<B: Backend> ModuleVisitor<B> for Shapes {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<B, D>>) {
        self.0.push(param.val().dims().to_vec());
    }
}

fn shapes<B: Backend>(network: &QNetwork<B>) -> Vec<Vec<usize>> {
    let mut v = Shapes(Vec::new());
    network.visit(&mut v);
    v.0
}

/// Collects parameter values in visiting order.
struct Values(Vec<f32>);

impl<B: Backend> ModuleVisitor<B> for Values {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<B, D>>) {
        let data = param.val().into_data().convert::<f32>();
        self.0
            .extend(data.to_vec::<f32>().expect("converted to f32"));
    }
}

/// Every parameter value of a network (a Q network, the price network, any Burn
/// module), in visiting order: what two networks of one configuration must share to
/// compute the same thing. (Their weight files differ even then, in the random
/// parameter ids that Burn records.)
///
/// # Examples
/// ```
/// use afg_learn::{InferBackend, nets::{NetworkConfig, parameter_values}};
/// let config = NetworkConfig::afgnet(5, 7);
/// let a = config.init::<InferBackend>(&Default::default());
/// let b = config.init::<InferBackend>(&Default::default());
/// assert_eq!(parameter_values(&a), parameter_values(&b)); // one seed, one network
/// ```
pub fn parameter_values<B: Backend>(network: &impl Module<B>) -> Vec<f32> {
    let mut v = Values(Vec::new());
    network.visit(&mut v);
    v.0
}

/// Whether every parameter seen so far is finite.
struct Finite(bool);

impl<B: Backend> ModuleVisitor<B> for Finite {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<B, D>>) {
        if self.0 {
            let data = param.val().into_data().convert::<f32>();
            self.0 = data.iter::<f32>().all(f32::is_finite);
        }
    }
}

/// Whether every weight of a network is finite (no NaN or infinity): checked when
/// weights are loaded and after every training update.
pub(crate) fn weights_are_finite<B: Backend>(network: &impl Module<B>) -> bool {
    let mut v = Finite(true);
    network.visit(&mut v);
    v.0
}

/// The weights header at `header_path`, checked: its format and version, and the
/// network's shape within [`crate::nets::NETWORK_LIMITS`].
fn read_header(header_path: &Path) -> Result<WeightsHeader, LearnError> {
    let text = std::fs::read_to_string(header_path)
        .map_err(|e| weights_error(header_path, e.to_string()))?;
    if text.contains(WEIGHTS_FORMAT) && crate::format::is_older(&text) {
        return Err(weights_error(
            header_path,
            crate::format::older_format_hint(),
        ));
    }
    let header: WeightsHeader = serde_json::from_str(&text)
        .map_err(|e| weights_error(header_path, format!("not a weights header: {e}")))?;
    if header.format != WEIGHTS_FORMAT || header.version != WEIGHTS_VERSION {
        return Err(weights_error(
            header_path,
            format!(
                "format {} version {}, expected {WEIGHTS_FORMAT} version {WEIGHTS_VERSION}",
                header.format, header.version
            ),
        ));
    }
    header
        .network
        .check()
        .map_err(|reason| weights_error(header_path, reason))?;
    Ok(header)
}

/// Loads weights saved by [`save_network`].
///
/// # Errors
/// [`LearnError::Weights`] for a missing or malformed header, a header of another
/// format or version, a corrupt or truncated record, parameters whose shapes differ
/// from the network the header describes, or a NaN or infinite weight.
pub fn load_network<B: Backend>(
    stem: &Path,
    device: &B::Device,
) -> Result<(NetworkConfig, QNetwork<B>), LearnError> {
    let header_path = with_extension(stem, "json");
    let header = read_header(&header_path)?;
    let fresh = header.network.init::<B>(device);
    let expected = shapes(&fresh);
    let recorder = NamedMpkFileRecorder::<FullPrecisionSettings>::new();
    let record_path = with_extension(stem, "mpk");
    // Burn panics when a record holds another network variant; report that as an error too.
    let loaded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        recorder.load::<<QNetwork<B> as Module<B>>::Record>(record_path.clone(), device)
    }));
    let record = match loaded {
        Ok(Ok(record)) => record,
        Ok(Err(e)) => {
            return Err(weights_error(
                &record_path,
                format!("unreadable weights ({e}); corrupt or truncated?"),
            ));
        }
        Err(_) => {
            return Err(weights_error(
                &record_path,
                "the record holds another kind of network than its header says",
            ));
        }
    };
    // An optional part (AFGNet's price head) that the record has and the header does
    // not would be dropped without a word by `load_record`.
    if let (QNetworkRecord::AfgNet(r), NetworkConfig::AfgNet(c)) = (&record, &header.network)
        && r.price.is_some() != c.price_head
    {
        return Err(weights_error(
            &record_path,
            "the record and its header disagree on the price head",
        ));
    }
    let network = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        fresh.load_record(record)
    })) {
        Ok(network) => network,
        Err(_) => {
            return Err(weights_error(
                &record_path,
                "the record holds another kind of network than its header says",
            ));
        }
    };
    if shapes(&network) != expected {
        return Err(weights_error(
            &record_path,
            format!(
                "parameter shapes differ from the {} network its header describes",
                header.network.name()
            ),
        ));
    }
    if !weights_are_finite(&network) {
        return Err(weights_error(
            &record_path,
            "holds a NaN or infinite weight; the network would compute nothing meaningful",
        ));
    }
    Ok((header.network, network))
}
