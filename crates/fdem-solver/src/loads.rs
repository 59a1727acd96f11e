//! Supports, prescribed velocities, surface pressure and their time
//! histories.

use fdem_element::Vec2;

use crate::model::Release;
use crate::passes::PressureFacet;

/// The external loads of a run: what the node pass adds to the elements'
/// forces besides contact (ARCHITECTURE.md, "One step"), with the time
/// histories that scale them.
#[derive(Default)]
pub(crate) struct Loads {
    /// Supports and prescribed velocities, per node.
    pub constraints: Vec<Constraint>,
    /// Time histories of the constraints.
    pub amplitudes: Vec<Amplitude>,
    /// Their values at the current time.
    pub amplitude_values: Vec<f64>,
    /// Pressure loads as given, by ancestor node pairs (re-resolved after
    /// topology changes).
    pub pressure_loads: Vec<PressureLoad>,
    /// Pressure loads resolved on the surface.
    pub pressure: Vec<PressureFacet>,
    /// Pressure forces per boundary node at `xⁿ` (N).
    pub pressure_force: Vec<Vec2>,
    /// Gravity (m/s²).
    pub gravity: Vec2,
    /// The loads of gradual excavations still falling to zero
    /// ([`crate::Release`]).
    pub released: Vec<Release>,
    /// Their sum per node at the current whole step (N; empty while none
    /// acts): an external load of the node pass
    /// ([`Simulation::update_release`](crate::Simulation::update_release)).
    pub release_force: Vec<Vec2>,
}

impl Loads {
    /// Sets each time history's value at time `t` (s).
    pub fn eval_amplitudes(&mut self, t: f64) {
        for (val, a) in self.amplitude_values.iter_mut().zip(&self.amplitudes) {
            *val = a.at(t);
        }
    }

    /// Sums the loads of the gradual excavations at time `t` (s) into
    /// [`Self::release_force`] (`nodes` entries) and drops those that
    /// have fallen to zero (the array is emptied once none is left, so a
    /// run without them pays nothing).
    pub fn update_release(&mut self, t: f64, nodes: usize) {
        self.released.retain(|r| r.share(t) > 0.0);
        self.release_force.clear();
        if self.released.is_empty() {
            return;
        }
        self.release_force.resize(nodes, [0.0; 2]);
        for r in &self.released {
            let s = r.share(t);
            for (&v, f) in r.nodes.iter().zip(&r.forces) {
                let out = &mut self.release_force[v as usize];
                out[0] += s * f[0];
                out[1] += s * f[1];
            }
        }
    }
}

/// A piecewise-linear time history `factor(t)` through `(times[i],
/// values[i])`, constant beyond the ends. Times strictly increasing (s).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Amplitude {
    /// Sample times (s), strictly increasing, at least one.
    pub times: Vec<f64>,
    /// Factors at those times (−).
    pub values: Vec<f64>,
}

impl Amplitude {
    /// The factor at time `t`.
    pub fn at(&self, t: f64) -> f64 {
        let (ts, vs) = (&self.times, &self.values);
        if t <= ts[0] {
            return vs[0];
        }
        let last = ts.len() - 1;
        if t >= ts[last] {
            return vs[last];
        }
        let i = ts.partition_point(|&s| s <= t);
        let (t0, t1) = (ts[i - 1], ts[i]);
        vs[i - 1] + (vs[i] - vs[i - 1]) * (t - t0) / (t1 - t0)
    }

    pub(crate) fn check(&self, index: usize) -> Result<(), String> {
        let ok_len = !self.times.is_empty() && self.times.len() == self.values.len();
        let finite = self.times.iter().chain(&self.values).all(|v| v.is_finite());
        let increasing = self.times.windows(2).all(|w| w[1] > w[0]);
        if ok_len && finite && increasing {
            Ok(())
        } else {
            Err(format!("amplitude {index}: needs equally many finite times and values, times strictly increasing"))
        }
    }
}

/// A kinematic condition on one node: each flagged component of the
/// velocity is held at `value × amplitude(t)` (m/s). A fixed support is a
/// value of zero; a roller fixes one component.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Constraint {
    /// The node.
    pub node: u32,
    /// Which components are prescribed: `[x, y]`.
    pub fixed: [bool; 2],
    /// Prescribed velocity components (m/s).
    pub value: [f64; 2],
    /// Index of the amplitude, or `None` for a constant factor 1.
    pub amplitude: Option<u32>,
}

/// Follower pressure on one boundary facet: `pressure × amplitude(t)` (Pa,
/// positive pushes into the body) acting normal to the current facet, split
/// equally between its two nodes.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PressureLoad {
    /// The facet's nodes (either order; the body side is found from the mesh).
    pub nodes: [u32; 2],
    /// Pressure (Pa).
    pub pressure: f64,
    /// Index of the amplitude, or `None` for a constant factor 1.
    pub amplitude: Option<u32>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amplitude_interpolates_and_clamps() {
        let a = Amplitude { times: vec![0.0, 1.0, 3.0], values: vec![0.0, 2.0, 2.0] };
        assert_eq!(a.at(-1.0), 0.0);
        assert_eq!(a.at(0.25), 0.5);
        assert_eq!(a.at(2.0), 2.0);
        assert_eq!(a.at(9.0), 2.0);
        assert!(Amplitude { times: vec![1.0, 1.0], values: vec![0.0, 1.0] }.check(0).is_err());
    }
}
