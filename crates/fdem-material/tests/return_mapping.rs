//! Every return region of the Mohr–Coulomb + Rankine law against an
//! independent brute-force solver: try every combination of the six planes,
//! solve each with nalgebra, keep the consistent ones. The law's answer must
//! be one of them. The brute force below is written from the paper's
//! yield functions (A.1, B.1) directly, not from the law's code.

use fdem_material::mohr_coulomb_rankine::{surface, CANDIDATES, RETURN_ORDER};
use fdem_material::principal::{Order, Spectral};
use fdem_material::{CrackBand, Elastic, Geometry, MohrCoulombRankine, PlasticState, Softening};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

const DEG: f64 = std::f64::consts::PI / 180.0;

/// A tiny deterministic generator (xorshift), so failures reproduce.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// The paper's Table 1 rock with a chosen band.
fn palabora() -> MohrCoulombRankine {
    let e = Elastic::new(60e9, 0.25).unwrap();
    MohrCoulombRankine::new(e, 8e6, 55.0 * DEG, 9.0 * DEG, 1e6, 70.0, CrackBand::Oliver).unwrap()
}

struct Brute {
    e: f64,
    nu: f64,
    c: f64,
    phi: f64,
    psi: f64,
    h: f64,
}

impl Brute {
    /// Yield function value and gradients of plane `k` (0..6: (1,3), (1,2),
    /// (2,3) Mohr–Coulomb as ½(σi − σj) + ½(σi + σj) sin φ − c cos φ, then
    /// σ1, σ2, σ3 − σy), and its potential gradient.
    fn plane(&self, k: usize, s: &Vector3<f64>, sy: f64) -> (f64, Vector3<f64>, Vector3<f64>) {
        let mc = |i: usize, j: usize| {
            let f = 0.5 * (s[i] - s[j]) + 0.5 * (s[i] + s[j]) * self.phi.sin() - self.c * self.phi.cos();
            let mut a = Vector3::zeros();
            a[i] = 0.5 + 0.5 * self.phi.sin();
            a[j] = -0.5 + 0.5 * self.phi.sin();
            let mut n = Vector3::zeros();
            n[i] = 0.5 + 0.5 * self.psi.sin();
            n[j] = -0.5 + 0.5 * self.psi.sin();
            (f, a, n)
        };
        match k {
            0 => mc(0, 2),
            1 => mc(0, 1),
            2 => mc(1, 2),
            _ => {
                let mut a = Vector3::zeros();
                a[k - 3] = 1.0;
                (s[k - 3] - sy, a, a)
            }
        }
    }

    fn elasticity(&self) -> Matrix3<f64> {
        let l = self.e * self.nu / ((1.0 + self.nu) * (1.0 - 2.0 * self.nu));
        let g = self.e / (2.0 * (1.0 + self.nu));
        Matrix3::from_fn(|i, j| l + if i == j { 2.0 * g } else { 0.0 })
    }

    /// All consistent returns from trial `s` with fracturing strain `kappa`,
    /// as (mask, exhausted branch, stress).
    fn consistent(&self, s: Vector3<f64>, kappa: f64, ft: f64, tol: f64) -> Vec<(u8, bool, Vector3<f64>)> {
        let c = self.elasticity();
        let g2 = self.e / (1.0 + self.nu);
        let mut out = Vec::new();
        for mask in 1u8..64 {
            let planes: Vec<usize> = (0..6).filter(|k| mask & (1 << k) != 0).collect();
            let n = planes.len();
            // strength path: linear softening; if that ends below zero, zero strength
            // linear softening while strength remains; once exhausted (or
            // exhausted within this step) zero strength and no softening
            let exhausted_before = ft - self.h * kappa <= 0.0;
            for floor in [false, true] {
                if floor && exhausted_before {
                    continue;
                }
                let (h, sy0) = if floor || exhausted_before { (0.0, 0.0) } else { (self.h, ft - self.h * kappa) };
                let mut g = DMatrix::zeros(n, n);
                let mut rhs = DVector::zeros(n);
                for (i, &pi) in planes.iter().enumerate() {
                    let (f, a, _) = self.plane(pi, &s, sy0);
                    rhs[i] = f;
                    for (j, &pj) in planes.iter().enumerate() {
                        let (_, _, nb) = self.plane(pj, &s, sy0);
                        g[(i, j)] = a.dot(&(c * nb)) - if pi >= 3 && pj >= 3 { h } else { 0.0 };
                    }
                }
                // a rank-deficient system (coinciding conditions) has a line of
                // multipliers: accept it if some point of the line is >= 0
                let svd = g.clone().svd(true, true);
                let smax = svd.singular_values.max();
                let rank = svd.singular_values.iter().filter(|&&v| v > 1e-10 * smax).count();
                if rank + 1 < n || smax == 0.0 {
                    continue;
                }
                let Ok(mut x) = svd.solve(&rhs, 1e-10 * smax) else {
                    continue;
                };
                if x.iter().any(|v| !v.is_finite()) || (&g * &x - &rhs).norm() > 1e-6 * rhs.norm().max(1.0) {
                    continue;
                }
                if rank + 1 == n {
                    let vt = svd.v_t.as_ref().unwrap();
                    let k = (0..n).min_by(|&a, &b| svd.singular_values[a].total_cmp(&svd.singular_values[b])).unwrap();
                    let v: Vec<f64> = (0..n).map(|j| vt[(k, j)]).collect();
                    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
                    for j in 0..n {
                        if v[j].abs() < 1e-12 {
                            continue;
                        }
                        let t = -x[j] / v[j];
                        if v[j] > 0.0 {
                            lo = lo.max(t);
                        } else {
                            hi = hi.min(t);
                        }
                    }
                    if lo > hi {
                        continue;
                    }
                    let t = if lo.is_finite() && hi.is_finite() {
                        0.5 * (lo + hi)
                    } else if lo.is_finite() {
                        lo
                    } else {
                        hi.min(0.0)
                    };
                    for j in 0..n {
                        x[j] += t * v[j];
                    }
                }
                let mut new = s;
                let mut dk = 0.0;
                for (j, &pj) in planes.iter().enumerate() {
                    let (_, _, nb) = self.plane(pj, &s, sy0);
                    new -= x[j] * (c * nb);
                    if pj >= 3 {
                        dk += x[j];
                    }
                }
                let sy = sy0 - h * dk;
                if sy < 0.0 {
                    continue;
                }
                // the exhausted branch needs the step to soften all the way
                if floor && (self.h == 0.0 || kappa + dk < ft / self.h * (1.0 - 1e-12) || pl_rankine(mask) == 0) {
                    continue;
                }
                let ok = x.iter().all(|&v| v * g2 >= -tol)
                    && new[0] >= new[1] - tol
                    && new[1] >= new[2] - tol
                    && (0..6).all(|k| {
                        let (f, _, _) = self.plane(k, &new, sy);
                        // MC planes here are half the law's; compare in the law's scale
                        (if k < 3 { 2.0 * f } else { f }) <= tol
                    });
                if ok {
                    out.push((mask, floor, new));
                }
            }
        }
        out
    }
}

fn pl_rankine(mask: u8) -> u8 {
    mask & 0b111000
}

fn sorted(v: [f64; 3]) -> [f64; 3] {
    let mut s = v;
    s.sort_by(|a, b| b.total_cmp(a));
    s
}

#[test]
fn returns_agree_with_brute_force_in_every_region() {
    let law = palabora();
    let mut rng = Rng(0x9e3779b97f4a7c15);
    let mut seen = std::collections::BTreeMap::new();
    let mut ambiguous = 0;
    let samples = 40_000;
    for _ in 0..samples {
        // trial principal stresses spread over tension and compression
        let scale = if rng.next() < 0.5 { 3e6 } else { 80e6 };
        let s =
            sorted([rng.range(-scale, 0.3 * scale), rng.range(-scale, 0.3 * scale), rng.range(-scale, 0.3 * scale)]);
        let band = rng.range(0.2, 3.0);
        let kappa_max = law.tensile_strength / law.softening_modulus(band);
        let kappa = if rng.next() < 0.3 { 0.0 } else { rng.range(0.0, 1.2 * kappa_max) };
        let brute =
            Brute { e: 60e9, nu: 0.25, c: 8e6, phi: 55.0 * DEG, psi: 9.0 * DEG, h: law.softening_modulus(band) };
        let tol = law.tolerance(s);
        let all = brute.consistent(Vector3::from(s), kappa, 1e6, tol);
        let f = law.yield_functions(s, (1e6 - brute.h * kappa).max(0.0));
        if f.iter().all(|&v| v <= tol) {
            continue; // elastic
        }
        let got = RETURN_ORDER.iter().find_map(|&(set, ex)| {
            law.principal_return(s, set, kappa, band, ex).filter(|r| law.is_consistent(r, tol)).map(|r| (set, r))
        });
        let (set, r) = got.unwrap_or_else(|| panic!("no consistent return for {s:?}, kappa {kappa}"));
        // the selection rule (module notes), applied to the brute force:
        // fewest planes, Mohr–Coulomb-only first, linear softening first
        let key = |mask: u8, floor: bool| (mask.count_ones(), mask & 0b111000 != 0, floor);
        let best = all
            .iter()
            .map(|(m, fl, _)| key(*m, *fl))
            .min()
            .unwrap_or_else(|| panic!("brute force found nothing for {s:?}"));
        let chosen: Vec<&Vector3<f64>> =
            all.iter().filter(|(m, fl, _)| key(*m, *fl) == best).map(|(_, _, v)| v).collect();
        let same = |b: &Vector3<f64>| (0..3).all(|k| (b[k] - r.stress[k]).abs() <= 1e-7 * scale);
        assert!(chosen.iter().any(|b| same(b)), "{s:?} kappa {kappa}: law {set:#b} {:?}, brute {all:?}", r.stress);
        if chosen.iter().any(|b| !same(b)) {
            ambiguous += 1;
        }
        // the active planes are exactly on their surfaces, the others inside
        let fr = law.yield_functions(r.stress, r.strength);
        for (k, &bit) in surface::ALL.iter().enumerate() {
            if set & bit != 0 {
                assert!(fr[k].abs() <= tol, "plane {bit} of {set:#b}: f = {}", fr[k]);
                assert!(r.multipliers[k] >= -tol / (2.0 * law.elastic.mu));
            } else {
                assert!(fr[k] <= tol);
                assert_eq!(r.multipliers[k], 0.0);
            }
        }
        assert!(r.stress[0] >= r.stress[1] - tol && r.stress[1] >= r.stress[2] - tol);
        *seen.entry(set).or_insert(0usize) += 1;
    }
    // every region except the Mohr–Coulomb apex (unreachable while the
    // tension cut-off lies inside it, f_t < c cot φ) is visited
    for set in CANDIDATES {
        if set == surface::MC {
            continue;
        }
        assert!(seen.get(&set).copied().unwrap_or(0) > 0, "region {set:#b} never reached: {seen:?}");
    }
    // under the rule the return is unique
    assert_eq!(ambiguous, 0);
}

/// The update's own search (strength and yield functions shared by every
/// set it tries, a set refused as soon as a multiplier is below what the
/// consistency check accepts) picks the same set and gives the same
/// stress, to the bit, as trying every set in [`RETURN_ORDER`] through the
/// public `principal_return` and `is_consistent`: over 20 000 random
/// trials on cracked points (tension and compression, softening and fully
/// softened).
#[test]
fn update_picks_the_first_consistent_set_in_order() {
    let law = palabora();
    let mut rng = Rng(0x2545f4914f6cdd1d);
    let geometry = Geometry { e1: [1.0, 0.0], e2: [0.4, 0.9] };
    let mut plastic = 0;
    for _ in 0..20_000 {
        let scale = if rng.next() < 0.5 { 3e6 } else { 80e6 };
        let trial = [
            rng.range(-scale, 0.3 * scale),
            rng.range(-scale, 0.3 * scale),
            rng.range(-scale, 0.3 * scale),
            rng.range(-0.3 * scale, 0.3 * scale),
        ];
        let band = rng.range(0.2, 3.0);
        let kappa_max = law.tensile_strength / law.softening_modulus(band);
        let kappa = if rng.next() < 0.3 { 0.0 } else { rng.range(0.0, 1.2 * kappa_max) };
        let mut state = PlasticState { kappa, crack_band: band, ..Default::default() };
        let got = law.update(trial, trial, &mut state, || geometry);
        let sp = Spectral::of(trial);
        let (s, order) = Order::sort(sp.a, sp.b, trial[2]);
        let tol = law.tolerance(s);
        let reference = RETURN_ORDER.iter().find_map(|&(set, ex)| {
            law.principal_return(s, set, kappa, band, ex).filter(|r| law.is_consistent(r, tol)).map(|r| (set, r))
        });
        if got.active == 0 {
            // elastic: no plane is violated beyond the tolerance
            let f = law.yield_functions(s, (law.tensile_strength - law.softening_modulus(band) * kappa).max(0.0));
            assert!(f.iter().all(|&v| v <= tol), "{trial:?}: elastic but f = {f:?}");
            continue;
        }
        plastic += 1;
        let (set, r) = reference.unwrap_or_else(|| panic!("{trial:?}: no consistent set in order"));
        assert_eq!(got.active, set, "{trial:?} kappa {kappa} band {band}");
        let [a, b, zz] = order.unsort(r.stress);
        let stress = sp.compose(a, b, zz);
        assert_eq!(got.stress.map(f64::to_bits), stress.map(f64::to_bits), "{trial:?}");
        assert_eq!(state.kappa.to_bits(), r.kappa.to_bits());
    }
    assert!(plastic > 5_000, "only {plastic} plastic trials");
}

/// The update's quick elastic test (bounds on the principal stresses
/// without the square root) never calls a point elastic that the full test
/// (principal stresses, tolerance) calls plastic, nor the reverse: over
/// trials put within a relative 1e-18 to 1e-6 of the Mohr–Coulomb main
/// plane and of the tension cut-off, on and off the principal axes (no
/// shear, no in-plane deviator), where the bounds are tightest.
#[test]
fn quick_elastic_test_agrees_with_the_full_one_at_the_yield_surface() {
    let law = palabora();
    let mut rng = Rng(0x9e3779b97f4a7c15);
    let geometry = Geometry { e1: [1.0, 0.0], e2: [0.4, 0.9] };
    let (sp, k) = (law.friction.sin(), 2.0 * law.cohesion * law.friction.cos());
    let (mut elastic, mut plastic) = (0, 0);
    for i in 0..40_000 {
        let band = rng.range(0.2, 3.0);
        let kappa_max = law.tensile_strength / law.softening_modulus(band);
        let kappa = if rng.next() < 0.3 { 0.0 } else { rng.range(0.0, 1.2 * kappa_max) };
        let sy = (law.tensile_strength - law.softening_modulus(band) * kappa).max(0.0);
        // principal values: σ3 below, σ1 on the main plane or the cut-off
        let s3 = rng.range(-60e6, sy);
        let on_main = (k + s3 * (1.0 - sp)) / (1.0 + sp);
        let s1 = if rng.next() < 0.5 { on_main.min(sy) } else { sy.max(s3) };
        let nudge = (if rng.next() < 0.5 { -1.0 } else { 1.0 }) * 10f64.powf(rng.range(-18.0, -6.0));
        let s1 = s1 * (1.0 + nudge) + nudge * 1e6;
        let s2 = rng.range(s3, s1.max(s3));
        // which two are in plane, at which angle
        let (a, b, zz) = match i % 3 {
            0 => (s1, s3, s2),
            1 => (s1, s2, s3),
            _ => (s2, s3, s1),
        };
        let th = match (i / 3) % 4 {
            0 => 0.0,
            1 => std::f64::consts::FRAC_PI_2,
            _ => rng.range(-1.6, 1.6),
        };
        let (m, h) = (0.5 * (a + b), 0.5 * (a - b));
        let trial = [m + h * (2.0 * th).cos(), m - h * (2.0 * th).cos(), zz, h * (2.0 * th).sin()];
        // the full test, as `update` writes it
        let spec = Spectral::of(trial);
        let (s, _) = Order::sort(spec.a, spec.b, trial[2]);
        let tol = law.tolerance(s);
        let main = s[0] * (1.0 + sp) - s[2] * (1.0 - sp) - k;
        let full_elastic = main <= tol && s[0] - sy <= tol;
        let mut state = PlasticState { kappa, crack_band: band, ..Default::default() };
        let got = law.update(trial, trial, &mut state, || geometry);
        assert_eq!(got.active == 0, full_elastic, "{trial:?} kappa {kappa} band {band}: main {main} tol {tol}");
        if full_elastic {
            elastic += 1;
        } else {
            plastic += 1;
        }
    }
    assert!(elastic > 5_000 && plastic > 5_000, "{elastic} elastic, {plastic} plastic");
    // a NaN in any component is not masked: it stays in the stress
    for k in 0..4 {
        let mut trial = [-5e6, -8e6, -3e6, 1e6];
        trial[k] = f64::NAN;
        let mut state = PlasticState::default();
        let got = law.update(trial, trial, &mut state, || geometry);
        assert!(got.stress.iter().any(|v| v.is_nan()), "component {k}: {:?}", got.stress);
    }
}

#[test]
fn apex_is_reached_when_the_cutoff_touches_it() {
    // f_t = c cot φ puts the tension apex on the Mohr–Coulomb apex; a trial
    // far out in triaxial tension goes to σ1 = σ2 = σ3 = c cot φ.
    let e = Elastic::new(60e9, 0.25).unwrap();
    let (c, phi) = (1e6, 30.0 * DEG);
    let law = MohrCoulombRankine::new(e, c, phi, 10.0 * DEG, c / phi.tan(), 1e9, CrackBand::Oliver).unwrap();
    let s = [9e6, 8e6, 7e6];
    let r = law.principal_return(s, surface::MC, 0.0, 1e-6, false).unwrap();
    let apex = c / phi.tan();
    for k in 0..3 {
        assert!((r.stress[k] - apex).abs() < 1e-6 * apex, "{:?}", r.stress);
    }
}

#[test]
fn update_flows_along_the_potential_gradients() {
    // Δεᵖ = C⁻¹ (σ^tr − σ): its principal components must be a non-negative
    // combination of the active potential gradients (2.8), and the elastic
    // part must reproduce the returned stress.
    let law = palabora();
    let geometry = Geometry { e1: [1.0, 0.0], e2: [0.3, 0.9] };
    let mut rng = Rng(42);
    for _ in 0..5000 {
        let t = [rng.range(-80e6, 3e6), rng.range(-80e6, 3e6), rng.range(-80e6, 3e6), rng.range(-20e6, 20e6)];
        let mut state = PlasticState::default();
        let u = law.update(t, t, &mut state, || geometry);
        if u.active == 0 {
            continue;
        }
        let dsig: Vec<f64> = (0..4).map(|k| t[k] - u.stress[k]).collect();
        let de = law.elastic.strain([dsig[0], dsig[1], dsig[2], dsig[3]]);
        for k in 0..4 {
            assert!(
                (de[k] - state.plastic_strain[k]).abs() <= 1e-9 * de.iter().fold(1e-12, |m: f64, v| m.max(v.abs()))
            );
        }
        let sp = Spectral::of(t);
        let (_, order) = Order::sort(sp.a, sp.b, t[2]);
        // principal plastic strains on the trial's axes
        let h = 0.5 * (de[0] - de[1]);
        let m = 0.5 * (de[0] + de[1]);
        let r = h * sp.cos2 + de[3] * sp.sin2;
        let principal = [m + r, m - r, de[2]];
        let sorted_e: Vec<f64> = order.slot.iter().map(|&k| principal[k as usize]).collect();
        // least-squares combination of the active potentials
        let active: Vec<u8> = surface::ALL.iter().copied().filter(|b| u.active & b != 0).collect();
        let a = DMatrix::from_fn(3, active.len(), |i, j| law.gradients(active[j]).1[i]);
        let x = a.clone().svd(true, true).solve(&DVector::from_row_slice(&sorted_e), 1e-14).unwrap();
        let resid = (&a * &x - DVector::from_row_slice(&sorted_e)).norm();
        let size = sorted_e.iter().map(|v| v.abs()).fold(1e-30, f64::max);
        assert!(resid <= 1e-8 * size, "flow not along potentials: {resid} vs {size}, set {:#b}", u.active);
        assert!(x.iter().all(|&v| v >= -1e-8 * size), "negative multiplier {x:?}");
    }
}

#[test]
fn softening_dissipates_the_fracture_energy() {
    // Uniaxial strain in x driven well past full softening: the fracture
    // dissipation per unit volume integrates to G_f / h_c (B.4).
    let e = Elastic::new(30e9, 0.0).unwrap();
    let law = MohrCoulombRankine::new(e, 8e6, 40.0 * DEG, 0.0, 1e6, 100.0, CrackBand::Oliver).unwrap();
    let geometry = Geometry { e1: [0.5, 0.0], e2: [0.0, 0.5] };
    let mut state = PlasticState::default();
    let mut s = [0.0; 4];
    let mut dissipated = 0.0;
    let d_eps = 2e-7;
    for _ in 0..20_000 {
        let trial = law.elastic.trial(s, [d_eps, 0.0, 0.0], 1.0);
        let u = law.update(s, trial, &mut state, || geometry);
        dissipated += u.fracture_dissipation + u.plastic_dissipation;
        s = u.stress;
    }
    assert!((state.crack_band - 0.5).abs() < 1e-12, "band {}", state.crack_band);
    let expected = law.fracture_energy / state.crack_band;
    assert!((dissipated - expected).abs() < 1e-3 * expected, "{dissipated} vs {expected}");
    assert!(law.failure_factor(&state) > 1.0 && s[0].abs() < 1e-6);
}

/// Petersson's bilinear curve (`f_t/3` at `0.8 G_f/f_t`, zero at
/// `3.6 G_f/f_t`) in a band of 0.5 m driven in uniaxial strain past full
/// softening, with steps of a hundredth of the kink's opening spread over
/// the band: the stress follows `f_t s(w/w_c)` at the crack opening
/// `w = κ h_c` within 10⁻⁶ of `f_t` (a return lands on the curve, also
/// when a step crosses the kink), the
/// dissipation per unit volume integrates to `G_f / h_c` within 0.1%, and
/// the stress is zero from `w_c` on.
#[test]
fn bilinear_softening_follows_the_curve_and_dissipates_the_fracture_energy() {
    let e = Elastic::new(30e9, 0.0).unwrap();
    let (ft, gf) = (1e6, 100.0);
    let law = MohrCoulombRankine::new(e, 8e6, 40.0 * DEG, 0.0, ft, gf, CrackBand::Oliver)
        .unwrap()
        .with_softening(Softening::PETERSSON)
        .unwrap();
    let w_c = 3.6 * gf / ft;
    assert!((law.critical_opening() - w_c).abs() < 1e-12 * w_c);
    // the steepest branch, 3 f_t / w_c over 0.5 m, against E
    assert!((law.snap_back_size() - 30e9 * w_c / (3.0 * ft)).abs() < 1e-9);
    let geometry = Geometry { e1: [0.5, 0.0], e2: [0.0, 0.5] };
    let mut state = PlasticState::default();
    let mut s = [0.0; 4];
    let mut dissipated = 0.0;
    let d_eps = 0.8 * gf / ft / 0.5 / 100.0;
    let mut worst: f64 = 0.0;
    for _ in 0..600 {
        let trial = law.elastic.trial(s, [d_eps, 0.0, 0.0], 1.0);
        let u = law.update(s, trial, &mut state, || geometry);
        dissipated += u.fracture_dissipation + u.plastic_dissipation;
        s = u.stress;
        if state.crack_band > 0.0 {
            let w = state.kappa * state.crack_band;
            worst = worst.max((s[0] - ft * Softening::PETERSSON.stress(w / w_c)).abs());
        }
    }
    assert!(worst < 1e-6 * ft, "stress off the curve by {worst} Pa");
    assert!((state.crack_band - 0.5).abs() < 1e-12, "band {}", state.crack_band);
    let expected = gf / state.crack_band;
    assert!((dissipated - expected).abs() < 1e-3 * expected, "{dissipated} vs {expected}");
    assert!(law.failure_factor(&state) > 1.0 && s[0].abs() < 1e-6);
    // half way along the first branch: F = 0.1 reads as such
    let mut half = PlasticState { crack_band: 0.5, kappa: 0.1 * w_c / 0.5, ..Default::default() };
    assert!((law.failure_factor(&half) - 0.1).abs() < 1e-12);
    half.kappa = 0.0;
    assert_eq!(law.failure_factor(&half), 0.0);
}

/// The crack-band rules on a 3-4-5 right triangle: Oliver's band is the
/// width along the crack normal (3 m along x, 4 m along y) and at most the
/// hypotenuse, 5 m; the equivalent band is `√(4A/π)` with `A = 6 m²`
/// whatever the direction.
#[test]
fn crack_band_rules_give_the_triangle_widths() {
    let geometry = Geometry { e1: [3.0, 0.0], e2: [0.0, 4.0] };
    let e = Elastic::new(60e9, 0.25).unwrap();
    let law = |rule| MohrCoulombRankine::new(e, 8e6, 55.0 * DEG, 9.0 * DEG, 1e6, 70.0, rule).unwrap();
    let (oliver, equivalent) = (law(CrackBand::Oliver), law(CrackBand::Equivalent));
    assert!((oliver.band_width(&geometry, 0.0) - 3.0).abs() < 1e-15);
    assert!((oliver.band_width(&geometry, 90.0 * DEG) - 4.0).abs() < 1e-15);
    assert_eq!(oliver.largest_band_width(&geometry), 5.0);
    let hypotenuse = (-4.0f64).atan2(3.0);
    assert!((oliver.band_width(&geometry, hypotenuse) - 5.0).abs() < 1e-14);
    for k in 0..180 {
        assert!(oliver.band_width(&geometry, k as f64 * DEG) <= 5.0 * (1.0 + 1e-15));
    }
    let h = (24.0 / std::f64::consts::PI).sqrt();
    assert!((equivalent.largest_band_width(&geometry) - h).abs() < 1e-15);
    for k in 0..180 {
        assert_eq!(equivalent.band_width(&geometry, k as f64 * DEG), equivalent.largest_band_width(&geometry));
    }
}

#[test]
fn parameters_are_checked_by_name() {
    let e = Elastic::new(60e9, 0.25).unwrap();
    let make = |c: f64, phi: f64, psi: f64, ft: f64, gf: f64| {
        MohrCoulombRankine::new(e, c, phi * DEG, psi * DEG, ft, gf, CrackBand::Oliver)
            .map(|_| ())
            .map_err(|e| e.parameter)
    };
    assert_eq!(make(-1.0, 30.0, 0.0, 1e5, 10.0), Err("c"));
    assert_eq!(make(1e6, 90.0, 0.0, 1e5, 10.0), Err("phi"));
    assert_eq!(make(1e6, -1.0, 0.0, 1e5, 10.0), Err("phi"));
    assert_eq!(make(1e6, 30.0, 40.0, 1e5, 10.0), Err("psi"));
    assert_eq!(make(1e6, 30.0, -5.0, 1e5, 10.0), Err("psi"));
    assert_eq!(make(1e6, 30.0, 0.0, 0.0, 10.0), Err("ft"));
    assert_eq!(make(1e6, 30.0, 0.0, 2e6, 10.0), Err("ft"));
    assert_eq!(make(1e6, 30.0, 0.0, 1e5, 0.0), Err("Gf"));
    assert_eq!(make(1e6, 30.0, 10.0, 1e5, 10.0), Ok(()));
}
