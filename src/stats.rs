//! Counters: what each stage did (after pbrt-v4's `util/stats.h`). Stages count into plain
//! local variables in their hot loops and add them here once per line or band.

use serde::Serialize;
use std::collections::BTreeMap;

/// Named counters. A name ending in `_max` keeps the maximum instead of the sum.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
#[serde(transparent)]
pub struct Counters(BTreeMap<&'static str, u64>);

impl Counters {
    /// Adds `n` to counter `name` (or raises it to `n` for a `_max` counter).
    pub fn add(&mut self, name: &'static str, n: u64) {
        let v = self.0.entry(name).or_insert(0);
        if name.ends_with("_max") {
            *v = (*v).max(n);
        } else {
            *v += n;
        }
    }

    /// Adds every counter of `other`.
    pub fn merge(&mut self, other: &Counters) {
        for (&k, &v) in &other.0 {
            self.add(k, v);
        }
    }

    /// The value of counter `name` (0 when never counted).
    pub fn get(&self, name: &str) -> u64 {
        self.0.get(name).copied().unwrap_or(0)
    }

    /// All counters in name order.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, u64)> + '_ {
        self.0.iter().map(|(&k, &v)| (k, v))
    }
}

/// What a render did: the methods, the counters of each stage and the time of each step.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Stats {
    /// Visibility method name.
    pub visibility: String,
    /// Shadow method name.
    pub shadows: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// World polygons in the scene.
    pub polygons: usize,
    /// Light samples over all lights.
    pub light_samples: usize,
    /// Visibility counters.
    pub visibility_counters: Counters,
    /// Shadow counters.
    pub shadow_counters: Counters,
    /// Milliseconds per step (wall clock).
    pub time_ms: Times,
}

/// Milliseconds per step of a render (wall clock). The walk and the shading run line by line
/// in the same parallel pass; that pass's wall-clock time is split between them in the
/// proportion of their summed per-band times.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Times {
    /// Clipping and projecting the polygons.
    pub view: f64,
    /// Preparing the visibility stage and resolving every line into runs.
    pub visibility: f64,
    /// Preparing the shadow stage.
    pub shadow_prepare: f64,
    /// The shadow stage's per-line walk: which pixels of each run every light sample reaches.
    pub shadow_walk: f64,
    /// Shading every run.
    pub shading: f64,
    /// Rendering what the mirrors show, when a mirror is seen.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reflections: Option<f64>,
    /// The whole frame.
    pub total: f64,
}

impl Times {
    /// Each step but the total, by name, in the pipeline's order (`reflections` when there
    /// was one).
    pub fn steps(&self) -> impl Iterator<Item = (&'static str, f64)> {
        let steps = [
            ("view", Some(self.view)),
            ("visibility", Some(self.visibility)),
            ("shadow_prepare", Some(self.shadow_prepare)),
            ("shadow_walk", Some(self.shadow_walk)),
            ("shading", Some(self.shading)),
            ("reflections", self.reflections),
        ];
        steps.into_iter().filter_map(|(k, v)| Some((k, v?)))
    }
}
