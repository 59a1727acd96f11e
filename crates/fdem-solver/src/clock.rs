//! The integrator's clock: time, step count and the step sizes of the
//! variable-step central-difference scheme (DESIGN §4.2).
//!
//! Positions live at whole steps `tⁿ`, velocities at half steps: the step
//! just taken is `Δt^{n−½}` (from `tⁿ⁻¹` to `tⁿ`), the next one `Δt^{n+½}`.
//! The node pass integrates the velocity over their mean, and the
//! whole-step velocity is recovered over half the last one. The clock keeps
//! the two together: only [`Clock::advance`] moves time forward, and it
//! shifts the next step into the last; only [`Clock::set_step`] chooses
//! the next step, from the critical one and the settings.

use crate::model::Settings;

/// Time `tⁿ`, step count `n` and the steps on either side of `tⁿ`.
///
/// Checkpoints write it as its five fields in this order (postcard writes a
/// struct as its fields, so the bytes are those of the five loose fields
/// the saved state had before the clock was a struct).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct Clock {
    /// `tⁿ` (s).
    time: f64,
    /// `n`, the steps taken.
    step: u64,
    /// `Δt^{n+½}`, the next position step (s).
    dt: f64,
    /// `Δt^{n−½}`, the last position step (s); zero before the first step.
    dt_prev: f64,
    /// Critical step at the last stable-step evaluation, before the safety
    /// factor (s); infinite before the first.
    dt_critical: f64,
}

impl Default for Clock {
    fn default() -> Self {
        Clock { time: 0.0, step: 0, dt: 0.0, dt_prev: 0.0, dt_critical: f64::INFINITY }
    }
}

impl Clock {
    /// `tⁿ` (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// `n`, the steps taken.
    pub fn step(&self) -> u64 {
        self.step
    }

    /// `Δt^{n+½}`, the step the next advance takes (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// `Δt^{n−½}`, the step last taken (s); zero before the first step.
    pub fn dt_prev(&self) -> f64 {
        self.dt_prev
    }

    /// Critical step at the last stable-step evaluation, before the safety
    /// factor (s).
    pub fn dt_critical(&self) -> f64 {
        self.dt_critical
    }

    /// `Δt_avg = (Δt^{n−½} + Δt^{n+½}) / 2`, the step of the velocity
    /// update at `tⁿ`.
    pub fn dt_avg(&self) -> f64 {
        0.5 * (self.dt_prev + self.dt)
    }

    /// `t^{n+½}`, the time of the velocity update of the next step (s).
    pub fn mid_step(&self) -> f64 {
        self.time + 0.5 * self.dt
    }

    /// Whether a step has been taken since the start or the last restart
    /// of the run (with a zero last step the whole-step velocities are the
    /// half-step ones).
    pub fn started(&self) -> bool {
        self.dt_prev > 0.0
    }

    /// Whether the step count is a multiple of `interval` (the periodic
    /// checks after a step).
    pub fn every(&self, interval: u64) -> bool {
        self.step % interval == 0
    }

    /// Sets the critical step (s, before the safety factor) and from it the
    /// next step: the fixed step when the settings give one, else the
    /// safety factor times the critical step.
    pub fn set_step(&mut self, critical: f64, settings: &Settings) {
        self.dt_critical = critical;
        self.dt = settings.fixed_dt.unwrap_or(settings.safety * critical);
    }

    /// The step is taken: `tⁿ⁺¹ = tⁿ + Δt^{n+½}`, `n + 1`, and the step
    /// taken becomes the last one. The next step stays until
    /// [`Self::set_step`] changes it. Returns the step taken (s).
    pub fn advance(&mut self) -> f64 {
        let dt = self.dt;
        self.time += dt;
        self.step += 1;
        self.dt_prev = dt;
        dt
    }

    /// Time and step count back to zero (a restart after an equilibrium
    /// stage); the step sizes stay, so the scheme goes on from the same
    /// half-step velocities.
    pub fn restart(&mut self) {
        self.time = 0.0;
        self.step = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn advance_shifts_the_next_step_into_the_last() {
        let settings = Settings { fixed_dt: None, safety: 0.5, ..Settings::default() };
        let mut c = Clock::default();
        assert!(!c.started());
        c.set_step(2.0, &settings);
        assert_eq!((c.dt(), c.dt_critical(), c.dt_avg()), (1.0, 2.0, 0.5));
        assert_eq!(c.advance(), 1.0);
        assert_eq!((c.time(), c.step(), c.dt_prev()), (1.0, 1, 1.0));
        assert!(c.started() && c.every(1) && !c.every(2));
        c.set_step(1.0, &settings);
        assert_eq!((c.dt_avg(), c.mid_step()), (0.75, 1.25));
        c.restart();
        assert_eq!((c.time(), c.step(), c.dt(), c.dt_prev()), (0.0, 0, 0.5, 1.0));
    }

    #[test]
    fn a_fixed_step_overrides_the_critical_one() {
        let settings = Settings { fixed_dt: Some(0.1), ..Settings::default() };
        let mut c = Clock::default();
        c.set_step(2.0, &settings);
        assert_eq!((c.dt(), c.dt_critical()), (0.1, 2.0));
    }
}
