//! A run directory's trained model as an allocator, whatever its kind: the one
//! loader behind `afg solve --model`, Python's `load_model` and the tables.

use std::path::Path;

use afg_baseline::Allocator;

use crate::LearnError;
use crate::manifest::ModelKind;
use crate::policy::LearnedPolicy;
use crate::price::{PriceMode, PriceModel, PricePolicy};
use crate::run_dir::RunDir;
use crate::staffing::{StaffingModel, StaffingPolicy};

/// How the model of a directory is run ([`load_model`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ModelOptions {
    /// Robots per network evaluation (Q networks and sequential price models; default
    /// 1, the exact greedy rollout).
    pub block: Option<usize>,
    /// Q networks: balanced best-response sweeps after the rollout; staffing models: a
    /// welfare climb after the placement ([`StaffingPolicy::with_repair`](crate::staffing::StaffingPolicy::with_repair)).
    pub repair: bool,
    /// Price models: every robot uses the prices of the empty state.
    pub one_shot: bool,
    /// Q networks: roll out with the Burn network (the slow reference path).
    pub exact_burn: bool,
}

/// [`ModelOptions`] that do not go together, or not with the model found. The messages
/// name the options as [`ModelOptions`] does; a command line adds its flags.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum OptionConflict {
    /// Repair or the exact Burn rollout asked of a price model.
    #[error("repair and the exact Burn rollout apply to Q networks, not price models")]
    QNetworkOptionOnPriceModel,
    /// An option other than repair with a staffing model.
    #[error("block, one-shot and the exact Burn rollout do not apply to a staffing model")]
    OptionOnStaffingModel,
    /// A block size with the one-shot mode.
    #[error("a block size applies to the sequential mode, not the one-shot one")]
    BlockWithOneShot,
    /// The one-shot mode asked of a Q network.
    #[error("the one-shot mode applies to price models, not Q networks")]
    OneShotOnQNetwork,
    /// A block size other than 1 with the exact Burn rollout.
    #[error("the exact Burn rollout places one robot at a time (block 1)")]
    BlockWithExactBurn,
}

/// The trained model in run directory `dir` as an allocator, whatever its kind
/// ([`RunDir::kind`]: a Q network, a price model or a staffing model).
///
/// # Errors
/// [`LearnError::ModelOptions`] for options that do not apply to the model found, and
/// [`LearnError::Model`] if it cannot be loaded.
///
/// # Examples
/// ```
/// use afg_learn::run::{ModelOptions, load_model};
/// let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/paper/afgnet_ddqn_n20");
/// let one_shot = ModelOptions { one_shot: true, ..ModelOptions::default() };
/// let err = load_model(&dir, one_shot).err().unwrap(); // a Q network has no one-shot mode
/// assert!(err.to_string().starts_with("the one-shot mode applies to price models"));
/// assert!(load_model(&dir, ModelOptions::default()).is_ok());
/// ```
pub fn load_model(dir: &Path, options: ModelOptions) -> Result<Box<dyn Allocator>, LearnError> {
    let bad = |conflict: OptionConflict| Err(conflict.into());
    let loading = |source| LearnError::Model {
        path: dir.display().to_string(),
        source: Box::new(source),
    };
    let kind = RunDir::new(dir).kind().map_err(loading)?;
    if kind == ModelKind::StaffingModel {
        let repair = options.repair;
        if options
            != (ModelOptions {
                repair,
                ..ModelOptions::default()
            })
        {
            return bad(OptionConflict::OptionOnStaffingModel);
        }
        let policy = StaffingPolicy::load(&dir.join(StaffingModel::FILE_NAME))
            .map_err(loading)?
            .with_repair(repair);
        return Ok(Box::new(policy));
    }
    if kind == ModelKind::PriceModel {
        let price = dir.join(PriceModel::FILE_NAME);
        if options.repair || options.exact_burn {
            return bad(OptionConflict::QNetworkOptionOnPriceModel);
        }
        if options.one_shot && options.block.is_some() {
            return bad(OptionConflict::BlockWithOneShot);
        }
        let mode = if options.one_shot {
            PriceMode::OneShot
        } else {
            PriceMode::Sequential
        };
        let policy = PricePolicy::load(&price, mode)
            .and_then(|p| p.with_block(options.block.unwrap_or(1)))
            .map_err(loading)?;
        return Ok(Box::new(policy));
    }
    if options.one_shot {
        return bad(OptionConflict::OneShotOnQNetwork);
    }
    let policy = load_q_network(dir)?.with_repair(options.repair);
    let policy = match (options.exact_burn, options.block) {
        (true, Some(b)) if b != 1 => {
            return bad(OptionConflict::BlockWithExactBurn);
        }
        (true, _) => policy.exact_burn(),
        (false, block) => policy.with_block(block.unwrap_or(1)).map_err(loading)?,
    };
    Ok(Box::new(policy))
}

/// The Q network of the training run in `dir` (its final weights) as the greedy
/// policy, for callers that need more than an allocator (its network, its fast path).
///
/// # Errors
/// [`LearnError::Model`], naming the directory, if the weights cannot be loaded.
pub fn load_q_network(dir: &Path) -> Result<LearnedPolicy, LearnError> {
    LearnedPolicy::load(&RunDir::new(dir).weights()).map_err(|source| LearnError::Model {
        path: dir.display().to_string(),
        source: Box::new(source),
    })
}
