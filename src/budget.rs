//! The memory budget: work whose size is known before it starts (the frame's buffers, the
//! shadow maps, per-sample stencil state, a generated scene) is estimated first and refused
//! with a one-line error when it would need more than [`MEMORY_BUDGET`], instead of
//! aborting the process when an allocation fails halfway.

use crate::error::{Error, Result};

/// The most memory one estimated piece of work may ask for: 8 GiB.
pub const MEMORY_BUDGET: u64 = 8 << 30;

/// `Ok` when `bytes` (saturating arithmetic, so an overflowing estimate counts as too much)
/// fits the budget; otherwise an error saying what would need how much.
pub(crate) fn check(what: impl std::fmt::Display, bytes: u64) -> Result<()> {
    if bytes <= MEMORY_BUDGET {
        return Ok(());
    }
    Err(Error::OverBudget { what: what.to_string(), bytes, budget: MEMORY_BUDGET })
}

/// `a * b` saturating: estimates never wrap.
pub(crate) fn mul(a: u64, b: u64) -> u64 {
    a.saturating_mul(b)
}
