//! Meshes and specs shared by the solver's integration tests.
#![allow(dead_code)] // each test binary uses part of them

pub mod impact;

use fdem_solver::{ContactSpec, InterfaceSpec};

/// A unit square of `n × n` cells split into right triangles.
pub fn square(n: usize, size: f64) -> (Vec<[f64; 2]>, Vec<[u64; 3]>) {
    let h = size / n as f64;
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            p.push([i as f64 * h, j as f64 * h]);
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u64;
    let mut t = Vec::new();
    for j in 0..n {
        for i in 0..n {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (p, t)
}

/// Contact with one interface law for every facet and crack: normal and
/// shear stiffness `stiffness` (Pa/m), friction coefficient `friction`, no
/// cohesion, dashpot damping ratio `damping`.
pub fn one_law_contact(stiffness: f64, friction: f64, damping: f64) -> ContactSpec {
    ContactSpec {
        laws: vec![InterfaceSpec {
            normal_stiffness: stiffness,
            shear_stiffness: stiffness,
            friction,
            cohesion: 0.0,
            damping_ratio: damping,
        }],
        facet_laws: Vec::new(),
        crack_law: 0,
        margin: None,
    }
}
