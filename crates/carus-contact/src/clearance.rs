//! Temporal coherence for point queries (the "skin" of Verlet neighbour
//! lists): after a query, each point remembers where it was and how far it
//! may move before the answer can change from "no contact" to "contact";
//! until it has moved that far it is not queried again. Exact, because the
//! distance to a surface changes no faster than the point moves: the
//! skipped queries would all have answered "no contact".

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::collider::SurfacePoint;

/// Default skin, m: a query searches this far beyond the contact band, so a
/// point clear of the surface is skipped for up to that much motion.
/// Numerical: about a tenth of the head's radius, a few rigid steps' worth
/// of query cost saved per query made.
pub const DEFAULT_SKIN_M: f64 = 0.01;

/// Per point: where it was last queried and how far it may move from there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct Clearance {
    checked_at: Vec<DVec3>,
    free_travel: Vec<f64>,
}

impl Clearance {
    pub(crate) fn new(points: usize) -> Self {
        Clearance { checked_at: vec![DVec3::ZERO; points], free_travel: vec![0.0; points] }
    }

    pub(crate) fn len(&self) -> usize {
        self.free_travel.len()
    }

    /// Whether point `i`, now at `p`, is provably still out of contact.
    pub(crate) fn is_clear(&self, i: usize, p: DVec3) -> bool {
        p.distance_squared(self.checked_at[i]) < self.free_travel[i] * self.free_travel[i]
    }

    /// How far point `i`, now at `p`, has moved since its last query.
    pub(crate) fn travelled(&self, i: usize, p: DVec3) -> f64 {
        p.distance(self.checked_at[i])
    }

    /// Records a query of point `i` at `p` that searched `searched` far and
    /// found `hit`; contact means inside the surface by less than `band`.
    /// Keeps how far the point may now move without a new query.
    pub(crate) fn record(&mut self, i: usize, p: DVec3, hit: Option<&SurfacePoint>, band: f64, searched: f64) {
        let travel = match hit {
            // Outside: it must cross the surface first.
            Some(h) if h.signed_distance >= 0.0 => h.signed_distance,
            // Inside: in contact (query again next time) or deeper than the band.
            Some(h) => (-h.signed_distance - band).max(0.0),
            // Nothing within the search: the surface is at least that far.
            None => searched - band,
        };
        self.checked_at[i] = p;
        self.free_travel[i] = travel;
    }
}
