//! Supports, prescribed velocities, surface pressure and their time
//! histories.

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
