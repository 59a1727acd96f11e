//! Checkpoints: a restored run continues bit for bit, and damaged files are
//! refused with the reason (docs/checkpoints.md).

mod common;
use common::{one_law_contact, square};
use fdem_solver::{
    CheckpointError, Constraint, CrackBand, FractureSpec, LawSpec, MaterialSpec, ModelSpec, Simulation,
    CHECKPOINT_FORMAT,
};

/// A damped, gravity-loaded plate of `n × n` cells, supported at the bottom,
/// with a non-uniform initial velocity so every array carries information.
fn plate(n: usize) -> ModelSpec {
    let (points, triangles) = square(n, 1.0);
    let m = triangles.len();
    let np = points.len();
    let mut s = ModelSpec {
        points,
        triangles,
        materials: vec![MaterialSpec { density: 2000.0, young: 1e9, poisson: 0.25, law: LawSpec::Elastic }],
        element_material: vec![0; m],
        gravity: [0.0, -9.81],
        initial_velocity: Some((0..np).map(|i| [((i * 7) % 13) as f64 * 0.01, ((i * 3) % 5) as f64 * 0.01]).collect()),
        ..Default::default()
    };
    for i in 0..=n as u32 {
        s.constraints.push(Constraint { node: i, fixed: [true, true], value: [0.0; 2], amplitude: None });
    }
    s.settings.mass_damping = 2.0;
    s.settings.dt_interval = 7;
    s
}

#[test]
fn restored_run_continues_bit_for_bit_on_another_thread_count() {
    let mut a = Simulation::new(plate(40), 2).unwrap();
    a.step(150).unwrap();
    let saved = a.checkpoint_bytes(b"user block");
    a.step(200).unwrap();

    let (mut b, user) = Simulation::from_checkpoint_bytes(&saved, 1).unwrap();
    assert_eq!(user, b"user block");
    assert_eq!(b.steps(), 150);
    b.step(200).unwrap();
    // equal checkpoints = equal state, every array bit for bit
    assert!(a.checkpoint_bytes(b"") == b.checkpoint_bytes(b""), "restored run diverged");
    assert_eq!(a.energies(), b.energies());
}

#[test]
fn checkpoint_file_is_written_atomically_and_read_back() {
    let dir = std::env::temp_dir().join(format!("fdem-ckpt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("run.ckpt");
    let mut a = Simulation::new(plate(8), 1).unwrap();
    a.step(20).unwrap();
    a.write_checkpoint(&path, b"x").unwrap();
    assert!(!dir.join("run.ckpt.tmp").exists());
    let (b, user) = Simulation::read_checkpoint(&path, 2).unwrap();
    assert_eq!(user, b"x");
    assert_eq!(b.time(), a.time());
    let missing = Simulation::read_checkpoint(&dir.join("none.ckpt"), 1).err().unwrap();
    assert!(matches!(missing, CheckpointError::Io(ref m) if m.contains("none.ckpt")), "{missing}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Re-seals the header checksum after editing the header.
fn reseal(b: &mut [u8]) {
    let crc = crc32fast::hash(&b[..36]);
    b[36..40].copy_from_slice(&crc.to_le_bytes());
}

/// Checkpoint `v` with the f64 at byte `at` set to `value`, both checksums
/// made to match: a consistent file holding a bad value.
fn with_f64_at(v: &[u8], at: usize, value: f64) -> Vec<u8> {
    let mut bad = v.to_vec();
    bad[at..at + 8].copy_from_slice(&value.to_le_bytes());
    let crc = crc32fast::hash(&bad[40..]);
    bad[32..36].copy_from_slice(&crc.to_le_bytes());
    reseal(&mut bad);
    bad
}

#[test]
fn damaged_files_are_refused_with_the_reason() {
    let mut sim = Simulation::new(plate(6), 1).unwrap();
    sim.step(10).unwrap();
    let good = sim.checkpoint_bytes(b"meta");
    let read = |b: &[u8]| Simulation::from_checkpoint_bytes(b, 1).err().expect("must be refused");

    assert_eq!(read(b"not a checkpoint at all"), CheckpointError::NotACheckpoint);
    assert_eq!(read(&[]), CheckpointError::NotACheckpoint);
    // every truncation is caught, at any length
    for len in [8, 20, 39, 40, 41, good.len() / 2, good.len() - 1] {
        let e = read(&good[..len]);
        assert!(matches!(e, CheckpointError::Truncated { .. }), "length {len}: {e}");
    }
    // a flipped bit anywhere in the data or the header
    for pos in [12, 20, 33, 45, good.len() / 2, good.len() - 1] {
        let mut b = good.clone();
        b[pos] ^= 0x10;
        let e = read(&b);
        assert!(matches!(e, CheckpointError::Corrupted(_)), "byte {pos}: {e}");
    }
    // a newer format
    let mut b = good.clone();
    b[8..12].copy_from_slice(&(CHECKPOINT_FORMAT + 1).to_le_bytes());
    reseal(&mut b);
    let e = read(&b);
    assert_eq!(e, CheckpointError::NewerFormat { found: CHECKPOINT_FORMAT + 1, supported: CHECKPOINT_FORMAT });
    assert!(e.to_string().contains("newer fdem"), "{e}");
    // trailing bytes
    let mut b = good.clone();
    b.push(0);
    assert!(matches!(read(&b), CheckpointError::Corrupted(_)));
}

#[test]
fn a_consistent_checksum_over_inconsistent_data_is_refused() {
    // a hand-made file: valid checksums, but the state's node arrays are cut
    let sim = Simulation::new(plate(4), 1).unwrap();
    let mut good = sim.checkpoint_bytes(b"");
    // declare one byte less of state, drop the last state byte, and reseal
    let s_len = u64::from_le_bytes(good[16..24].try_into().unwrap());
    good.truncate(40 + s_len as usize - 1);
    good[16..24].copy_from_slice(&(s_len - 1).to_le_bytes());
    let crc = crc32fast::hash(&good[40..]);
    good[32..36].copy_from_slice(&crc.to_le_bytes());
    reseal(&mut good);
    let e = Simulation::from_checkpoint_bytes(&good, 1).err().unwrap();
    assert!(matches!(e, CheckpointError::Invalid(_)), "{e}");
}

/// `bytes` as an older format would have written it: the last `block`
/// bytes of the state cut off, the version set to `version`, resealed.
fn downgrade(bytes: &[u8], version: u32, block: usize) -> Vec<u8> {
    let s_len = u64::from_le_bytes(bytes[16..24].try_into().unwrap()) as usize;
    let mut old = bytes[..40].to_vec();
    old.extend_from_slice(&bytes[40..40 + s_len - block]);
    old.extend_from_slice(&bytes[40 + s_len..]);
    old[8..12].copy_from_slice(&version.to_le_bytes());
    old[16..24].copy_from_slice(&((s_len - block) as u64).to_le_bytes());
    let crc = crc32fast::hash(&old[40..]);
    old[32..36].copy_from_slice(&crc.to_le_bytes());
    reseal(&mut old);
    old
}

/// Bytes of a postcard varint holding `n`.
fn varint(n: usize) -> usize {
    (usize::BITS - n.max(1).leading_zeros()).div_ceil(7) as usize
}

/// Bytes of the format-4 block of a run that never renumbered, of `m`
/// elements at the start: the setting `None`, four empty maps, the base
/// element count `m` and a zero count.
fn format4_len(m: usize) -> usize {
    1 + 4 + varint(m) + 1
}

/// Bytes of the format-6 block with `nb` boundary nodes under contact (0
/// without contact): two lists of `nb` dashpots of four f64 each.
fn format6_len(nb: usize) -> usize {
    2 * (varint(nb) + 32 * nb)
}

/// Bytes of the format-7 block (lineage): a varint count and every
/// element's parent as a varint.
fn format7_len(sim: &Simulation) -> usize {
    varint(sim.n_elements()) + sim.element_parents().iter().map(|&p| varint(p as usize)).sum::<usize>()
}

/// Bytes of the format-8 block of a run without excavation stages: the
/// bond offsets (a varint count and two f64 per bond), the local damping
/// (one f64) and two empty lists (stage release times, gradual
/// excavations).
fn format8_len(sim: &Simulation) -> usize {
    varint(sim.bonds().len()) + 16 * sim.bonds().len() + 8 + 2
}

/// Bytes of the format-9 block of a run without bonds: an empty list of
/// bond laws and each material's `G_II` (a varint count and one f64 each).
fn format9_len(sim: &Simulation, materials: usize) -> usize {
    assert!(sim.bonds().is_empty());
    1 + varint(materials) + 8 * materials
}

/// Bytes of the format-10 block of a run with linear softening and no
/// kinked bonds: each material's curve (a varint count and a one-byte
/// variant each) and each bond's kink (a varint count and a one-byte
/// `None` each).
fn format10_len(sim: &Simulation, materials: usize) -> usize {
    varint(materials) + materials + varint(sim.bonds().len()) + sim.bonds().len()
}

/// Bytes of the format-11 block of a run without periodic renumbering
/// (the interval `None`).
const FORMAT11_LEN: usize = 1;

/// Bytes of the format-12 block of a run whose contact memories hold no
/// offset (two empty lists).
const FORMAT12_LEN: usize = 2;

/// The plate with contact on its own surface (a dashpot of damping ratio
/// 0.1).
fn plate_with_contact(n: usize) -> ModelSpec {
    let mut spec = plate(n);
    spec.contact = Some(one_law_contact(1e10, 0.5, 0.1));
    spec
}

#[test]
fn a_format_1_file_still_reads_with_physical_masses() {
    // format 2 appends the mass-scaling block (density factors, setting,
    // energy term) to the format-1 state, format 3 the corner contacts
    // (two empty lists without contact), format 4 the renumbering block;
    // cut them off, mark the file as
    // format 1 and reseal: it must read back as the same run
    let mut a = Simulation::new(plate(6), 1).unwrap();
    a.step(30).unwrap();
    let v3 = a.checkpoint_bytes(b"meta");
    let m = a.triangles().len();
    // postcard: varint length + m f64, `None` (one byte), one f64; two
    // zero lengths; the format-4, format-6 and format-7 blocks
    let v1 = downgrade(
        &v3,
        1,
        varint(m)
            + 8 * m
            + 1
            + 8
            + 2
            + format4_len(m)
            + format6_len(0)
            + format7_len(&a)
            + format8_len(&a)
            + format9_len(&a, 1)
            + format10_len(&a, 1)
            + (FORMAT11_LEN + FORMAT12_LEN),
    );
    let (mut b, user) = Simulation::from_checkpoint_bytes(&v1, 1).unwrap();
    assert_eq!(user, b"meta");
    assert!(b.mass_scale().iter().all(|&s| s == 1.0) && b.mass_scale().len() == m);
    assert!(b.checkpoint_bytes(b"meta") == v3, "format 1 read back differs");
    a.step(20).unwrap();
    b.step(20).unwrap();
    assert!(a.checkpoint_bytes(b"") == b.checkpoint_bytes(b""));
}

#[test]
fn a_format_2_file_with_contact_reads_without_corner_contacts() {
    // the plate with contact on its own surface, before its first step:
    // every corner's second contact is empty, which is what a format-2
    // file restores with, so the two must continue identically
    let mut a = Simulation::new(plate_with_contact(6), 1).unwrap();
    let v3 = a.checkpoint_bytes(b"");
    let nb = 4 * 6;
    // two lists of nb: an empty memory is 22 bytes (facet u32::MAX as a
    // 5-byte varint, two f64, `None`), an empty contact 70 (facet, 7 f64,
    // a bool); then the format-4, format-6 and format-7 blocks
    let blocks = format4_len(a.n_elements())
        + format6_len(nb)
        + format7_len(&a)
        + format8_len(&a)
        + format9_len(&a, 1)
        + format10_len(&a, 1)
        + (FORMAT11_LEN + FORMAT12_LEN);
    let v2 = downgrade(&v3, 2, 2 * varint(nb) + nb * (22 + 70) + blocks);
    let (mut b, _) = Simulation::from_checkpoint_bytes(&v2, 1).unwrap();
    assert!(b.checkpoint_bytes(b"") == v3, "format 2 read back differs");
    a.step(20).unwrap();
    b.step(20).unwrap();
    assert!(a.checkpoint_bytes(b"") == b.checkpoint_bytes(b""));
}

#[test]
fn a_format_4_file_keeps_its_crack_directions() {
    // formats 1–4 kept each point's crack direction as an angle (rad),
    // format 5 as a direction code: a format-4 file must read back with the
    // angles it holds. The plate stretched and sheared from its top until
    // its points soften in tension, each along its own direction.
    let n = 8;
    let mut spec = plate(n);
    spec.materials[0].law = LawSpec::MohrCoulombRankine {
        cohesion: 1e6,
        friction: 0.5,
        dilation: 0.1,
        tensile_strength: 1e5,
        fracture_energy: 10.0,
        shear_fracture_energy: 10.0,
        crack_band: CrackBand::Oliver,
        softening: fdem_solver::Softening::Linear,
    };
    let top = (n * (n + 1)) as u32;
    for i in top..=top + n as u32 {
        let value = [0.3 * (i - top) as f64 / n as f64, 0.5];
        spec.constraints.push(Constraint { node: i, fixed: [true, true], value, amplitude: None });
    }
    let mut a = Simulation::new(spec, 1).unwrap();
    a.step(300).unwrap();
    let codes: Vec<f64> = a.plastic_states().iter().map(|s| s.direction_code).collect();
    let cracked = a.failure_factors().iter().filter(|&&f| f > 0.0).count();
    assert!(cracked > 10, "only {cracked} points softened");
    assert!(codes.iter().filter(|&&c| c != 0.0).count() >= cracked);
    // the same bytes marked as format 4: each code is read as an angle
    let v6 = a.checkpoint_bytes(b"");
    let v4 = downgrade(
        &v6,
        4,
        format6_len(0)
            + format7_len(&a)
            + format8_len(&a)
            + format9_len(&a, 1)
            + format10_len(&a, 1)
            + (FORMAT11_LEN + FORMAT12_LEN),
    );
    let (b, _) = Simulation::from_checkpoint_bytes(&v4, 1).unwrap();
    let pi = std::f64::consts::PI;
    for (e, s) in b.plastic_states().iter().enumerate() {
        let d = (s.crack_angle() - codes[e]).rem_euclid(pi);
        assert!(d.min(pi - d) < 1e-15, "element {e}: angle {} for {}", s.crack_angle(), codes[e]);
    }
}

#[test]
fn a_format_5_file_reads_without_its_dashpots_and_a_format_6_file_with_them() {
    // format 6 appends every contact's dashpot (normal, coefficient,
    // spring force). Before the first step there is none, which is what a
    // format-5 file restores with: the two continue identically; a
    // format-6 file continues bit for bit on another thread count (with
    // dashpots in contact: the caving case's resume test,
    // tests/test_caving_resume.py).
    let mut a = Simulation::new(plate_with_contact(6), 1).unwrap();
    let v6 = a.checkpoint_bytes(b"");
    let v5 = downgrade(
        &v6,
        5,
        format6_len(4 * 6)
            + format7_len(&a)
            + format8_len(&a)
            + format9_len(&a, 1)
            + format10_len(&a, 1)
            + (FORMAT11_LEN + FORMAT12_LEN),
    );
    let (mut b, _) = Simulation::from_checkpoint_bytes(&v5, 1).unwrap();
    assert!(b.checkpoint_bytes(b"") == v6, "format 5 read back differs");
    a.step(40).unwrap();
    b.step(40).unwrap();
    assert!(a.checkpoint_bytes(b"") == b.checkpoint_bytes(b""));
    let (mut c, _) = Simulation::from_checkpoint_bytes(&a.checkpoint_bytes(b""), 2).unwrap();
    a.step(40).unwrap();
    c.step(40).unwrap();
    assert!(a.checkpoint_bytes(b"") == c.checkpoint_bytes(b""));
}

/// A 0.5 m × 0.1 m bar of 25 × 5 cells with contact and crack insertion
/// (cohesive bonds from a nodal failure factor of 0.02, as the Python
/// default), its middle column of cells weaker in tension, fixed at its
/// left end and pulled at its right end at 20 mm/s: cracks open across the
/// middle with their bonds, which then fail one by one.
fn bonded_bar() -> ModelSpec {
    let (nx, ny, h) = (25usize, 5usize, 0.02);
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u64;
    let points = (0..=ny).flat_map(|j| (0..=nx).map(move |i| [i as f64 * h, j as f64 * h])).collect();
    let (mut triangles, mut element_material) = (Vec::new(), Vec::new());
    for j in 0..ny {
        for i in 0..nx {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            element_material.extend([u32::from(i == nx / 2); 2]);
        }
    }
    let rock = |tensile_strength| MaterialSpec {
        density: 2700.0,
        young: 10e9,
        poisson: 0.2,
        law: LawSpec::MohrCoulombRankine {
            cohesion: 4e6,
            friction: 35f64.to_radians(),
            dilation: 5f64.to_radians(),
            tensile_strength,
            fracture_energy: 70.0,
            shear_fracture_energy: 70.0,
            crack_band: CrackBand::Oliver,
            softening: fdem_solver::Softening::Linear,
        },
    };
    let mut constraints = Vec::new();
    for j in 0..=ny {
        let fixed = [true, j == 0];
        constraints.push(Constraint { node: id(0, j) as u32, fixed, value: [0.0; 2], amplitude: None });
        let pull = [0.02, 0.0];
        constraints.push(Constraint { node: id(nx, j) as u32, fixed: [true, false], value: pull, amplitude: None });
    }
    let mut s = ModelSpec {
        points,
        triangles,
        materials: vec![rock(1.0e6), rock(0.8e6)],
        element_material,
        constraints,
        contact: Some(one_law_contact(1e11, 30f64.to_radians().tan(), 0.5)),
        fracture: Some(FractureSpec { params: Default::default(), interval: 5, insert_at: 0.02 }),
        ..Default::default()
    };
    s.settings.stiffness_damping = 1e-6;
    s
}

/// Issue 32 (4): a run with cohesive bonds restores bit for bit from a
/// checkpoint before its first crack, one right after cracks opened with
/// their bonds intact, and one just after a bond failed (fewer bonds, no
/// insertion since), on another thread count: the restored state is the
/// saved one (its checkpoint the same bytes, so the contact forces hold the
/// bonds' forces as the step left them), and the runs end equal.
#[test]
fn a_run_with_cohesive_bonds_restores_bit_for_bit_before_during_and_after_bond_failure() {
    let end = 5000;
    let mut a = Simulation::new(bonded_bar(), 2).unwrap();
    a.step(300).unwrap();
    assert_eq!((a.insertions(), a.bonds().len()), (Some(0), 0));
    let before = a.checkpoint_bytes(b"");
    while !a.bonds().iter().any(|b| b.max_opening > 0.0) {
        a.step(10).unwrap();
        assert!(a.steps() < end, "no crack opened with its bond");
    }
    let intact = a.checkpoint_bytes(b"");
    let mut most = a.bonds().len();
    loop {
        let insertions = a.insertions();
        a.step(10).unwrap();
        if a.insertions() == insertions && a.bonds().len() < most {
            break;
        }
        most = most.max(a.bonds().len());
        assert!(a.steps() < end, "no bond failed");
    }
    assert!(!a.bonds().is_empty());
    let failed = a.checkpoint_bytes(b"");
    a.step(end - a.steps()).unwrap();
    let reference = a.checkpoint_bytes(b"");
    for (label, saved) in [("before", before), ("intact", intact), ("failed", failed)] {
        let (mut b, _) = Simulation::from_checkpoint_bytes(&saved, 1).unwrap();
        assert!(b.checkpoint_bytes(b"") == saved, "{label}: the restored state is not the saved one");
        b.step(end - b.steps()).unwrap();
        assert!(b.checkpoint_bytes(b"") == reference, "{label}: the restored run diverged");
        assert_eq!(a.energies(), b.energies(), "{label}");
    }
}

#[test]
fn a_format_6_file_reads_without_lineage_and_a_bad_lineage_is_refused() {
    // format 7 appends every element's parent (the element crack insertion
    // cut it from). An uncracked model's elements are their own parents,
    // which is what a format-6 file restores with: the same bytes back.
    // (A cracked run's pieces are placed inside their model elements by
    // `recover_lineage`: tests/test_excavation.py.) The format-8 block (the
    // bonds' offsets, none here) is cut off with it.
    let mut a = Simulation::new(plate(6), 1).unwrap();
    a.step(10).unwrap();
    let v7 = a.checkpoint_bytes(b"");
    let m = a.n_elements();
    assert!(a.element_parents().iter().enumerate().all(|(e, &p)| p as usize == e));
    let v6 = downgrade(
        &v7,
        6,
        format7_len(&a) + format8_len(&a) + format9_len(&a, 1) + format10_len(&a, 1) + (FORMAT11_LEN + FORMAT12_LEN),
    );
    let (mut b, _) = Simulation::from_checkpoint_bytes(&v6, 1).unwrap();
    assert!(b.checkpoint_bytes(b"") == v7, "format 6 read back differs");
    // nothing to place: every element is one of the model's
    assert_eq!(b.recover_lineage(&a.reference_positions(), &a.triangles()), Ok(0));
    // the last element's parent made larger than its id (the last byte
    // of the state, a one-byte varint here)
    let s_len = u64::from_le_bytes(v7[16..24].try_into().unwrap()) as usize;
    let mut bad = v7.clone();
    let last =
        40 + s_len - 1 - format8_len(&a) - format9_len(&a, 1) - format10_len(&a, 1) - (FORMAT11_LEN + FORMAT12_LEN);
    assert_eq!(bad[last] as usize, m - 1);
    bad[last] = m as u8;
    let crc = crc32fast::hash(&bad[40..]);
    bad[32..36].copy_from_slice(&crc.to_le_bytes());
    reseal(&mut bad);
    let e = Simulation::from_checkpoint_bytes(&bad, 1).err().unwrap();
    assert!(matches!(e, CheckpointError::Invalid(ref s) if s.contains("lineage")), "{e}");
}

#[test]
fn a_format_7_file_reads_with_slack_bonds_and_bad_offsets_are_refused() {
    // format 8 appends each bond's offset (a varint count and two f64 per
    // bond). A run without bonds writes an empty list, which is what a
    // format-7 file restores with: the same bytes back.
    let mut a = Simulation::new(plate(6), 1).unwrap();
    a.step(10).unwrap();
    let v8 = a.checkpoint_bytes(b"");
    assert!(a.bonds().is_empty());
    let v7 =
        downgrade(&v8, 7, format8_len(&a) + format9_len(&a, 1) + format10_len(&a, 1) + (FORMAT11_LEN + FORMAT12_LEN));
    let (b, _) = Simulation::from_checkpoint_bytes(&v7, 1).unwrap();
    assert!(b.checkpoint_bytes(b"") == v8, "format 7 read back differs");
    // one offset where there is no bond: the count (the byte before the
    // local damping's f64 and the two empty lists) made 1 and two f64 put
    // after it
    let s_len = u64::from_le_bytes(v8[16..24].try_into().unwrap()) as usize;
    let f9 = format9_len(&a, 1) + format10_len(&a, 1) + (FORMAT11_LEN + FORMAT12_LEN);
    let mut state = v8[40..40 + s_len - f9 - 10].to_vec();
    *state.last_mut().unwrap() = 1;
    state.extend_from_slice(&[0u8; 16 + 8 + 2]);
    state.extend_from_slice(&v8[40 + s_len - f9..40 + s_len]);
    let mut bad = v8[..40].to_vec();
    bad.extend_from_slice(&state);
    bad[16..24].copy_from_slice(&(state.len() as u64).to_le_bytes());
    let crc = crc32fast::hash(&bad[40..]);
    bad[32..36].copy_from_slice(&crc.to_le_bytes());
    reseal(&mut bad);
    let e = Simulation::from_checkpoint_bytes(&bad, 1).err().unwrap();
    assert!(matches!(e, CheckpointError::Invalid(ref s) if s.contains("offsets")), "{e}");
}

/// Format 9 appends each bond's mixed-mode law (an option tag and six f64)
/// and each material's `G_II` (one f64). A format-8 file restores its
/// bonds with the isotropic law they were made with and gives its
/// materials `G_II = G_f`; a bond law whose damage lies outside [0, 1]
/// is refused.
#[test]
fn a_format_8_file_reads_with_isotropic_bonds_and_bad_bond_laws_are_refused() {
    let mut a = Simulation::new(bonded_bar(), 1).unwrap();
    while a.bonds().is_empty() {
        a.step(10).unwrap();
        assert!(a.steps() < 5000, "no crack opened with its bond");
    }
    let nb = a.bonds().len();
    assert!(a.bonds().iter().all(|b| b.mode.is_some()), "new bonds are mixed-mode");
    // the bar is pulled along x and cracks across it (straight and
    // kinked): each bond's normal points from its first node's side to its
    // second's, so that the crack opens (δ_n > 0)
    let mut probe = Simulation::from_checkpoint_bytes(&a.checkpoint_bytes(b""), 1).unwrap().0;
    probe.step(100).unwrap();
    let x = probe.positions();
    for bond in probe.bonds().iter() {
        let n = bond.mode.unwrap().normal;
        let [p, q] = bond.nodes.map(|v| v as usize);
        let dn = (x[q][0] - x[p][0] + bond.offset[0]) * n[0] + (x[q][1] - x[p][1] + bond.offset[1]) * n[1];
        assert!((n[0].hypot(n[1]) - 1.0).abs() < 1e-12, "normal {n:?}");
        assert!(dn > 0.0, "bond {:?} closed by {dn} m along its normal", bond.nodes);
    }
    let v9 = a.checkpoint_bytes(b"");
    let f10 = format10_len(&a, 2) + (FORMAT11_LEN + FORMAT12_LEN);
    let f9 = varint(nb) + nb * (1 + 6 * 8) + varint(2) + 2 * 8;
    let v8 = downgrade(&v9, 8, f9 + f10);
    let (mut b, _) = Simulation::from_checkpoint_bytes(&v8, 1).unwrap();
    assert!(b.bonds().iter().all(|b| b.mode.is_none()), "a format-8 file's bonds are isotropic");
    assert_eq!(b.bonds().len(), nb);
    // and so does a file it writes
    let (c, _) = Simulation::from_checkpoint_bytes(&b.checkpoint_bytes(b""), 1).unwrap();
    assert!(c.bonds().iter().all(|b| b.mode.is_none()));
    b.step(200).unwrap();
    assert!(b.energies().residual().is_finite());
    // the last bond's damage made 2
    let s_len = u64::from_le_bytes(v9[16..24].try_into().unwrap()) as usize;
    let bad = with_f64_at(&v9, 40 + s_len - f10 - (varint(2) + 2 * 8) - 8, 2.0);
    let e = Simulation::from_checkpoint_bytes(&bad, 1).err().unwrap();
    assert!(matches!(e, CheckpointError::Invalid(ref s) if s.contains("mixed-mode")), "{e}");
}

/// Format 10 appends each material's softening curve and each bond's
/// kink. The bonded bar with Petersson's bilinear curve: its young bonds
/// carry the rest of the curve's kink, a checkpoint keeps curves and
/// kinks, and the restored run continues bit for bit. A format-9 file
/// (the block cut off) reads with linear softening and straight bonds,
/// the only ones older builds had; a kink outside (0, 1) is refused.
#[test]
fn bilinear_curves_and_kinks_survive_a_restart_and_a_format_9_file_reads_linear() {
    let mut spec = bonded_bar();
    for m in &mut spec.materials {
        if let LawSpec::MohrCoulombRankine { softening, .. } = &mut m.law {
            *softening = fdem_solver::Softening::PETERSSON;
        }
    }
    let mut a = Simulation::new(spec, 1).unwrap();
    while a.bonds().is_empty() {
        a.step(10).unwrap();
        assert!(a.steps() < 5000, "no crack opened with its bond");
    }
    let nb = a.bonds().len();
    let kinked = a.bonds().iter().filter(|b| b.mode.and_then(|m| m.kink).is_some()).count();
    let last_kinked = a.bonds().last().and_then(|b| b.mode).is_some_and(|m| m.kink.is_some());
    assert!(kinked > 0, "no bond made before the kink has one");
    let v10 = a.checkpoint_bytes(b"");
    let (mut b, _) = Simulation::from_checkpoint_bytes(&v10, 2).unwrap();
    assert!(b.checkpoint_bytes(b"") == v10, "read back differs");
    a.step(300).unwrap();
    b.step(300).unwrap();
    assert!(a.checkpoint_bytes(b"") == b.checkpoint_bytes(b""), "the restored run went its own way");
    // the format-10 block: two materials (variant byte and two f64 each),
    // then each bond's option tag and, for a kink, two f64
    let f10 = varint(2) + 2 * 17 + varint(nb) + nb + 16 * kinked;
    let v9 = downgrade(&v10, 9, f10 + (FORMAT11_LEN + FORMAT12_LEN));
    let (c, _) = Simulation::from_checkpoint_bytes(&v9, 1).unwrap();
    assert!(c.bonds().iter().all(|b| b.mode.is_some_and(|m| m.kink.is_none())));
    // the last bond's kink made 2 in its traction (the last f64 of the state)
    assert!(c.bonds().len() == nb && last_kinked, "the last bond has no kink to spoil");
    let s_len = u64::from_le_bytes(v10[16..24].try_into().unwrap()) as usize;
    let bad = with_f64_at(&v10, 40 + s_len - (FORMAT11_LEN + FORMAT12_LEN) - 8, 2.0);
    let e = Simulation::from_checkpoint_bytes(&bad, 1).err().unwrap();
    assert!(matches!(e, CheckpointError::Invalid(ref s) if s.contains("kinks")), "{e}");
}

#[test]
fn a_format_10_file_with_renumbering_renumbers_every_thousand_steps() {
    // before format 11 a run with renumbering on also renumbered every
    // `RENUMBER_INTERVAL` steps: an older file restores that, a newer one
    // its own interval; an interval of 0 steps is refused
    let mut spec = plate(6);
    spec.settings.renumber = Some(0.05);
    let mut a = Simulation::new(spec, 1).unwrap();
    a.step(30).unwrap();
    let v11 = a.checkpoint_bytes(b"");
    let (b, _) = Simulation::from_checkpoint_bytes(&v11, 1).unwrap();
    assert_eq!(b.settings().renumber_every, None);
    let v10 = downgrade(&v11, 10, FORMAT11_LEN + FORMAT12_LEN);
    let (c, _) = Simulation::from_checkpoint_bytes(&v10, 1).unwrap();
    assert_eq!(c.settings().renumber_every, Some(fdem_solver::RENUMBER_INTERVAL));
    let s_len = u64::from_le_bytes(v11[16..24].try_into().unwrap()) as usize;
    // `Some(0)`: the option's tag 1, then the varint 0, in place of `None`
    let mut bad = v11[..40 + s_len - 1 - FORMAT12_LEN].to_vec();
    bad.extend_from_slice(&[1, 0]);
    bad.extend_from_slice(&v11[40 + s_len - FORMAT12_LEN..40 + s_len]);
    bad[16..24].copy_from_slice(&((s_len + 1) as u64).to_le_bytes());
    let crc = crc32fast::hash(&bad[40..]);
    bad[32..36].copy_from_slice(&crc.to_le_bytes());
    reseal(&mut bad);
    let e = Simulation::from_checkpoint_bytes(&bad, 1).err().unwrap();
    assert!(matches!(e, CheckpointError::Invalid(ref s) if s.contains("interval")), "{e}");
}

#[test]
fn contact_offsets_survive_a_restart_a_format_11_file_reads_without_and_bad_ones_are_refused() {
    // format 12 keeps the offsets of contacts taken up where their node was
    // found inside (docs/contact.md, item 7) as (boundary index, offset)
    // lists; a file without any holds two empty lists
    let mut a = Simulation::new(plate_with_contact(6), 1).unwrap();
    a.step(30).unwrap();
    let v12 = a.checkpoint_bytes(b"");
    let s_len = u64::from_le_bytes(v12[16..24].try_into().unwrap()) as usize;
    assert_eq!(&v12[40 + s_len - FORMAT12_LEN..40 + s_len], &[0, 0]);
    let v11 = downgrade(&v12, 11, FORMAT12_LEN);
    let (b, _) = Simulation::from_checkpoint_bytes(&v11, 1).unwrap();
    assert!(b.checkpoint_bytes(b"") == v12, "format 11 read back differs");
    // the first list given one entry: boundary node 0, `offset` m
    let with = |offset: f64, node: u8| {
        let mut v = v12[..40 + s_len - FORMAT12_LEN].to_vec();
        v.extend_from_slice(&[1, node]);
        v.extend_from_slice(&offset.to_le_bytes());
        v.push(0);
        v[16..24].copy_from_slice(&((s_len + 9) as u64).to_le_bytes());
        let crc = crc32fast::hash(&v[40..]);
        v[32..36].copy_from_slice(&crc.to_le_bytes());
        reseal(&mut v);
        v
    };
    let good = with(1e-3, 0);
    let (c, _) = Simulation::from_checkpoint_bytes(&good, 1).unwrap();
    assert!(c.checkpoint_bytes(b"") == good, "an offset did not survive the restart");
    for (bad, node) in [(-1e-3, 0), (f64::NAN, 0), (1e-3, 127)] {
        let e = Simulation::from_checkpoint_bytes(&with(bad, node), 1).err().unwrap();
        assert!(matches!(e, CheckpointError::Invalid(ref s) if s.contains("offsets")), "{bad} at {node}: {e}");
    }
}
