"""Notched three-point bending of a concrete beam (Petersson 1981).

The beam of Petersson's thesis (Crack growth and development of fracture
zones in plain concrete and similar materials, Lund, 1981): span 2.0 m,
depth 0.2 m, a notch to half the depth at mid-span; E = 30 GPa, ν = 0.2,
f_t = 3.33 MPa, G_f = 124 N/m (the values of Rots' analyses of it), in
plane strain, per metre of thickness. Petersson's beams were 50 mm thick
and peaked at about 0.8 kN, 16 kN/m.

The beam is meshed with gmsh (a band of ``size`` around the ligament,
twice that elsewhere; the notch is a 5 mm slot ending in a point), rests
on two point supports and is pressed down at mid-span at 5 mm/s through
a 20 mm steel pad, a body of its own in frictionless contact with the
beam and driven at its top face (a beam cut through under it parts
freely), mass-damped at a tenth of critical in its first bending mode:
quasi-static (before the first crack the pad's reaction exceeds the
supports' by the mass damping's drag on the beam, 1.5% of the peak).

The load is the mean of the pad's and the supports' reactions. Each
insertion sets the two halves of the span ringing between their support
and the pad, which holds mid-span (about 300 Hz; the mass damping gives
that mode 2.7% of critical, and it rings for some 20 ms); each half's
inertia in that mode loads its two ends alike, so the pad's and the
supports' reactions swing in opposition, and their mean is the load
that makes the bending moment at mid-span, (P + S)/2 · span/4. The
mean takes out that ringing (its 150–500 Hz content falls fivefold on 10
mm) and halves the drag, which a quasi-static test does not have.

Checks (``main`` returns them, tests/test_examples.py tests them):

- initial stiffness against the closed form: Timoshenko beam (bending and
  shear) plus the compliance of the notch as an edge crack in bending
  (Tada, Paris & Irwin, The Stress Analysis of Cracks Handbook, 2000,
  edge crack in pure bending, F(α) accurate to 0.2% for α ≤ 0.6), E' =
  E / (1 − ν²);
- the peak of the load averaged over 1 ms (the ringing of a few kHz
  that insertions leave averages out; each 0.1 ms sample is already the
  mean of readings every 10 steps) and its deflection;
- the largest change of the load across a sample (0.1 ms, 20–40
  fracture checks) at which cracks were inserted, the mean of the 1 ms
  after less that of the 1 ms before, as a fraction of the peak: an
  insertion must not release the load; beside it the largest such change
  at the samples with no insertion within 1 ms, the floor of this
  measure (the loading's trend, up to 3% of the peak per ms where the
  softening is steepest, and the ringing left);
- the same two on the pad's reaction alone, and the largest difference
  between the pad's and the supports' reactions beyond half the peak;
- the work of the load, for the energy a crack took;
- and, run far past the peak (``work_of_fracture``), the fracture energy
  against G_f times the ligament, less what the ligament still bridges
  (``bridged_energy``): the work-of-fracture test by which Petersson
  measured G_f.

    python examples/three_point_bending.py [--size 0.01] [--insert-at 0.02] [--softening bilinear] [--out beam_output]
"""

from __future__ import annotations

import argparse
import itertools
import math
import time
from pathlib import Path

import fdem
import numpy as np
from fdem.laboratory import STEEL

SPAN, LENGTH, DEPTH, NOTCH, SLOT, PAD = 2.0, 2.1, 0.2, 0.1, 0.005, 0.01
E, NU, RHO, FT, GF = 30e9, 0.2, 2400.0, 3.33e6, 124.0
SPEED = 5e-3  # m/s at the pad
PETERSSON_PEAK = 16e3  # N/m: about 0.8 kN on Petersson's 50 mm thick beams


def concrete(softening: str = "bilinear") -> fdem.MohrCoulombRankine:
    """The concrete: Rankine in tension softening along Petersson's
    bilinear curve, the one he fitted to this concrete (``ft/3`` at ``0.8
    Gf/ft``, zero at ``3.6 Gf/ft``), or ``softening="linear"``;
    Mohr–Coulomb (c 11.5 MPa, φ 30°: 40 MPa in compression) stays out of
    play."""
    return fdem.MohrCoulombRankine(E=E, nu=NU, rho=RHO, c=11.5e6, phi=30.0, psi=5.0, ft=FT, Gf=GF, softening=softening)


def beam_mesh(size: float, *, seed: int = 0) -> fdem.Mesh:
    """The notched beam meshed with gmsh: ``size`` (m) within 0.15 m of the
    ligament, ``2 size`` elsewhere (at least 20 mm). Node sets
    ``left_support``, ``right_support`` (one node each, 50 mm in from the
    ends) and ``under_pad`` (the top nodes within 10 mm of mid-span, where
    the pad rests); facet set ``beam_top`` (the top face)."""
    import gmsh

    coarse = max(0.02, 2 * size)
    xc, x0, x1 = LENGTH / 2, (LENGTH - SPAN) / 2, (LENGTH + SPAN) / 2
    outline = [
        (0, 0), (x0 - PAD, 0), (x0, 0), (x0 + PAD, 0),
        (xc - SLOT / 2, 0), (xc - SLOT / 2, NOTCH - SLOT / 2), (xc, NOTCH), (xc + SLOT / 2, NOTCH - SLOT / 2),
        (xc + SLOT / 2, 0), (x1 - PAD, 0), (x1, 0), (x1 + PAD, 0),
        (LENGTH, 0), (LENGTH, DEPTH), (xc + PAD, DEPTH), (xc - PAD, DEPTH), (0, DEPTH),
    ]  # fmt: skip
    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("Mesh.RandomSeed", int(seed))
        gmsh.model.add("beam")
        geo = gmsh.model.geo
        tags = [geo.addPoint(x, y, 0, coarse) for x, y in outline]
        lines = [geo.addLine(tags[k], tags[(k + 1) % len(tags)]) for k in range(len(tags))]
        geo.addPlaneSurface([geo.addCurveLoop(lines)])
        geo.synchronize()
        field = gmsh.model.mesh.field
        box = field.add("Box")
        for name, value in (("VIn", size), ("VOut", coarse), ("XMin", xc - 0.15), ("XMax", xc + 0.15)):
            field.setNumber(box, name, value)
        for name, value in (("YMin", -1.0), ("YMax", 1.0), ("Thickness", 0.3)):
            field.setNumber(box, name, value)
        field.setAsBackgroundMesh(box)
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
        gmsh.option.setNumber("Mesh.Algorithm", 6)
        gmsh.model.mesh.generate(2)
        mesh = fdem.Mesh.from_gmsh()
    finally:
        gmsh.finalize()
    points = mesh.points
    x, y = points[:, 0], points[:, 1]
    tol = 1e-9
    node_sets = {
        "left_support": np.flatnonzero((np.abs(x - x0) < tol) & (y < tol)),
        "right_support": np.flatnonzero((np.abs(x - x1) < tol) & (y < tol)),
        "under_pad": np.flatnonzero((np.abs(x - xc) <= PAD + tol) & (y > DEPTH - tol)),
    }
    mesh = mesh.with_sets(node_sets=node_sets).reordered()
    facets = mesh.boundary_facets()
    top = (mesh.points[facets][:, :, 1] > DEPTH - tol).all(axis=1)
    return mesh.with_sets(facet_sets={"beam_top": facets[top]})


def pad_mesh() -> fdem.Mesh:
    """The loading pad: a 20 mm square of 2 × 2 cells resting on the beam
    at mid-span, with the rectangle's groups (``top``, its driven face)
    and facet set ``faces`` (its whole boundary). Its triangles'
    altitudes (7.1 mm) are over twice the beam's smallest (2.4 to 3.4 mm,
    at the notch's tip), more than steel's wave speed is concrete's (1.6
    times), so the pad does not shorten the stable step nor the smallest
    split a crack may make (``min_size``)."""
    pad = fdem.Mesh.rectangle(2 * PAD, 2 * PAD, 2, 2, origin=(LENGTH / 2 - PAD, DEPTH))
    return pad.with_sets(facet_sets={"faces": pad.boundary_facets()})


def model(
    size: float = 0.01,
    *,
    insert_at: float | None = None,
    check_every: int | None = None,
    softening: str = "bilinear",
) -> fdem.Model:
    """The beam ready to run: supports (a pin and a roller), a steel pad
    resting on the beam at mid-span and driven down at ``SPEED`` (after a
    10 ms ramp) at its top face, frictional contact on crack faces and
    crack insertion with the library's defaults unless given; the
    concrete softens along ``softening`` (:func:`concrete`).

    The pad is a body of its own that meets the beam by contact, as the
    Brazilian test's jaws meet the disc: a beam cut through under it can
    then part or hinge freely, where prescribed beam nodes on either side
    of the crack would wedge its halves together. The pad meets the beam
    without friction (a pad on a roller bearing), so the top face under it
    stays free to shorten along the beam, as it was under prescribed
    nodes: with 30° of friction the pad's corners held it back, a tension
    in the top fibre against the bending, and the 20 mm beam read 1.5%
    stiffer. Every contact law has the stiffness the beam alone would get
    by default (``E / h``, E the concrete's, h the beam's mean boundary
    facet), so that the steel's modulus and the pad's facets leave the
    crack faces and their bonds as they were."""
    body, pad = beam_mesh(size), pad_mesh()
    facets = body.boundary_facets()
    k_n = E / float(np.linalg.norm(np.diff(body.points[facets], axis=1), axis=2).mean())
    mesh = fdem.Mesh.combine(
        body.with_sets(element_sets={"beam": np.arange(body.n_elements)}),
        pad.with_sets(element_sets={"body": np.arange(pad.n_elements)}),
        prefixes=("", "pad_"),
    )
    beam = fdem.Model(mesh, materials={"beam": concrete(softening), "pad_body": STEEL})
    beam.fix("left_support").fix("right_support", x=False, y=True)
    beam.prescribe_velocity("pad_top", vx=0.0, vy=-SPEED, amplitude=fdem.Amplitude.ramp(1e-2))
    options = {k: v for k, v in (("insert_at", insert_at), ("check_every", check_every)) if v is not None}
    rough = fdem.Interface(friction=30.0, normal_stiffness=k_n)
    smooth = fdem.Interface(friction=0.0, normal_stiffness=k_n)
    beam.contact(rough, interfaces={"beam_top": smooth, "pad_faces": smooth}).fracture(**options)
    return beam


def simulation(beam: fdem.Model, threads: int | None = None) -> fdem.Simulation:
    """The beam's simulation, mass-damped at a tenth of critical in the
    free span's first bending mode."""
    omega = (math.pi / SPAN) ** 2 * math.sqrt(E * DEPTH**2 / 12 / RHO)  # first bending mode (rad/s)
    return fdem.Simulation(beam, threads=threads, mass_damping=2 * 0.1 * omega)


def bridged_energy(deflection: float, softening: str = "bilinear") -> float:
    """The fracture energy (J/m) still to be dissipated in the ligament once
    mid-span has deflected ``deflection`` (m) well past the peak, for two
    rigid halves turning about the top of the mid-span section: each turns
    by φ = 2δ/S, the crack opens by w = 2φh at depth h below the top, and
    what the ligament has still to dissipate is G_f ∫ (1 − D(w(h))) dh =
    (1/2φ) ∫₀^{w_c} w σ(w) dw (by parts; D is the share of G_f the
    softening curve σ(w) of :func:`concrete` has dissipated at w, and the
    crack is taken as through the ligament, which it is when the load is a
    small part of the peak). The halves' own bending and the depth of the
    compression zone are left out, so it is the limit as the deflection
    grows: a beam in a work-of-fracture test (RILEM TC-50, Hillerborg
    1985) has dissipated G_f (D − a) less this."""
    rock = concrete(softening)
    w_c = rock.critical_opening
    kink = rock.softening_kink or (0.5, 0.5)  # linear: a "kink" on the line
    # the curve's corners (opening, traction); w σ(w) is quadratic between
    # them, so Simpson's rule on each piece is exact
    corners = [(0.0, FT), (kink[1] * w_c, kink[0] * FT), (w_c, 0.0)]
    moment = 0.0
    for (wa, sa), (wb, sb) in itertools.pairwise(corners):
        wm, sm = 0.5 * (wa + wb), 0.5 * (sa + sb)
        moment += (wb - wa) / 6 * (wa * sa + 4 * wm * sm + wb * sb)
    return moment / (2 * (2 * deflection / SPAN))


def work_of_fracture(
    size: float = 0.01, deflection: float = 5e-3, *, softening: str = "bilinear", threads: int | None = None
) -> dict[str, float]:
    """Runs the beam to ``deflection`` (m, several times the peak's) and
    returns the fracture energy it dissipated (J/m), against G_f times the
    ligament (D − a) and against that less :func:`bridged_energy`: a beam
    broken through its ligament dissipates G_f per unit of it, on every
    mesh (issue 33, point 4; Petersson measured G_f so, from the work of
    the load on such beams)."""
    sim = simulation(model(size, softening=softening), threads)
    start = time.perf_counter()
    sim.run(until=5e-3 + deflection / SPEED, progress=False)
    fracture = sim.energies()["fracture"]
    ligament = GF * (DEPTH - NOTCH)
    expected = ligament - bridged_energy(deflection, softening)
    return {
        "fracture": fracture,
        "gf_ligament": ligament,
        "expected": expected,
        "ratio_to_ligament": fracture / ligament,
        "ratio_to_expected": fracture / expected,
        "crack_length_vertical": sim.crack_length(along=(0.0, 1.0)),
        "cracks": float(sim.insertions),
        "wall_s": time.perf_counter() - start,
    }


def closed_form_stiffness() -> float:
    """Load per unit deflection (N/m per m) of the notched beam, elastic:
    bending S³/(48 E'I) and shear S/(4 κ G W) of a Timoshenko beam (κ =
    5/6) plus the notch as an edge crack of depth a in pure bending,
    C = (2/E') ∫₀^a (K/P)² da with K = (6M/W²) √(πa) F(a/W), M = PS/4."""
    e_plane = E / (1 - NU**2)
    shear_modulus = E / (2 * (1 + NU))
    bending = SPAN**3 / (48 * e_plane * DEPTH**3 / 12)
    shear = SPAN / (4 * (5 / 6) * shear_modulus * DEPTH)
    alpha = np.linspace(0.0, NOTCH / DEPTH, 4001)
    f = 1.122 - 1.40 * alpha + 7.33 * alpha**2 - 13.08 * alpha**3 + 14.0 * alpha**4
    g = alpha * f**2
    integral = float(np.sum(0.5 * (g[1:] + g[:-1]) * np.diff(alpha)))
    notch = (2 / e_plane) * (1.5 * SPAN / DEPTH**2) ** 2 * math.pi * DEPTH**2 * integral
    return 1.0 / (bending + shear + notch)


def main(
    size: float = 0.01,
    *,
    insert_at: float | None = None,
    check_every: int | None = None,
    softening: str = "bilinear",
    deflection: float = 0.8e-3,
    threads: int | None = None,
    out: str | None = "beam_output",
) -> dict[str, float]:
    """Runs the beam to ``deflection`` (m) at the pad; returns the checks
    (see the module's docstring) and writes ``beam.csv`` and ``beam.png``
    into ``out`` if given."""
    beam = model(size, insert_at=insert_at, check_every=check_every, softening=softening)
    sim = simulation(beam, threads)
    start, until = time.perf_counter(), 5e-3 + deflection / SPEED
    rows = []
    while sim.time < until:
        # each sample is the mean of the reactions read every 10 steps
        # over 0.1 ms: a reading at one instant would alias the ringing
        # (kHz and above) that insertions leave
        end, pad_sum, support_sum, reads = sim.time + 1e-4, 0.0, 0.0, 0
        while sim.time < end:
            sim.step(10)
            pad_sum += sim.reaction("pad_top")["force"][1]
            support_sum -= sim.reaction("left_support")["force"][1] + sim.reaction("right_support")["force"][1]
            reads += 1
        deflection = -sim.probe("under_pad")["displacement"][1]
        rows.append((sim.time, deflection, pad_sum / reads, support_sum / reads, sim.insertions))
    t, d, pad, support, cracks = np.array(rows).T
    # the load on the beam: the mean of the pad's and the supports'
    # reactions. Each insertion sets the two halves of the span ringing
    # between their support and the pad (about 300 Hz on 10 mm; the mass
    # damping, tuned to the first mode of the free span, gives it 2.7% of
    # critical); each half's inertia then loads its two ends alike, so the
    # pad and the supports swing in opposition and their mean keeps the
    # load that bends the beam at mid-span (docs/fracture.md)
    load = 0.5 * (pad + support)
    data = np.column_stack([t, d, load, pad, support, cracks])
    mean, k = _peak(load)
    # the stiffness once the ramp is over, before the peak and below 40%
    # of it; it depends on this window by ±5% (docs/fracture.md)
    elastic = (t > 1.2e-2) & (load < 0.4 * mean[k]) & (cracks == 0) & (np.arange(len(t)) < k)
    stiffness = float(np.polyfit(d[elastic], load[elastic], 1)[0]) if elastic.sum() > 2 else float("nan")
    change_at, change_else = _changes(load, cracks)
    pad_mean, pad_k = _peak(pad)
    pad_at, pad_else = _changes(pad, cracks)
    work = float(np.sum(0.5 * (load[1:] + load[:-1]) * np.diff(d)))
    summary = {
        "elements": float(beam.mesh.n_elements),
        "stiffness": stiffness,
        "closed_form_stiffness": closed_form_stiffness(),
        "peak_load": float(mean[k]),
        "peak_load_raw": float(load.max()),
        "peak_deflection": float(d[k]),
        "petersson_peak": PETERSSON_PEAK,
        "largest_change_at_insertion": change_at / mean[k],
        "largest_change_elsewhere": change_else / mean[k],
        "pad_peak_load": float(pad_mean[pad_k]),
        "pad_change_at_insertion": pad_at / pad_mean[pad_k],
        "pad_change_elsewhere": pad_else / pad_mean[pad_k],
        "pad_minus_supports": float(np.abs(pad - support)[load > 0.5 * mean[k]].max() / mean[k]),
        "cracks": float(cracks[-1]),
        **crack_path(sim),
        "work": work,
        "steps": float(sim.steps),
        "wall_s": time.perf_counter() - start,
    }
    if out is not None:
        write(Path(out), data, summary)
    return summary


def crack_path(sim: fdem.Simulation) -> dict[str, float]:
    """The crack above the notch at the end of the run: its direction
    (degrees from the vertical, positive leaning towards +x), the
    length-weighted mean offset of its faces from mid-span (m) and the
    height it has reached above the notch tip (m), from the crack faces
    within 0.1 m of mid-span above the tip; the line is the principal
    axis of the faces' midpoints weighted by their length. NaN without a
    crack."""
    faces = sim.crack_faces()
    a, b = faces[:, 0], faces[:, 1]
    mid, length = 0.5 * (a + b), np.linalg.norm(b - a, axis=1)
    xc = LENGTH / 2
    near = (np.abs(mid[:, 0] - xc) < 0.1) & (mid[:, 1] > DEPTH - NOTCH - 1e-3)
    if near.sum() < 2:
        return {"crack_angle_deg": float("nan"), "crack_offset": float("nan"), "crack_height": 0.0}
    w, p = length[near], mid[near]
    centre = (w[:, None] * p).sum(axis=0) / w.sum()
    d = p - centre
    cov = (w[:, None, None] * d[:, :, None] * d[:, None, :]).sum(axis=0)
    axis = np.linalg.eigh(cov)[1][:, -1]
    if axis[1] < 0:
        axis = -axis
    return {
        "crack_angle_deg": float(np.degrees(np.arctan2(axis[0], axis[1]))),
        "crack_offset": float(centre[0] - xc),
        "crack_height": float(p[:, 1].max() - (DEPTH - NOTCH)),
    }


def _peak(load: np.ndarray) -> tuple[np.ndarray, int]:
    """The load averaged over 1 ms (11 samples; the ringing of a few kHz
    that insertions leave averages out) and the sample of its peak."""
    mean = np.convolve(load, np.ones(11) / 11, mode="same")
    mean[:5], mean[-5:] = load[:5], load[-5:]
    return mean, int(np.argmax(mean))


def _changes(load: np.ndarray, cracks: np.ndarray, window: int = 10) -> tuple[float, float]:
    """The largest change of the load across a sample at which cracks were
    inserted, as the mean of the ``window`` samples after it less that of
    the ``window`` before (1 ms each: the wave an insertion sends and its
    ringing included, the ringing's own swing averaged out); and the
    largest such change across the samples with no insertion within
    ``window`` samples either side (the loading's own trend and the
    ringing left: the floor of this measure; a sample next to an
    insertion would measure that insertion again)."""
    total = np.concatenate([[0.0], np.cumsum(load)])
    inserted = np.r_[False, cracks[1:] > cracks[:-1]]
    near = np.convolve(inserted, np.ones(2 * window + 1), mode="same") > 0
    at, elsewhere = 0.0, 0.0
    for i in range(window, len(load) - window):
        change = abs((total[i + window] - total[i]) - (total[i] - total[i - window])) / window
        if inserted[i]:
            at = max(at, change)
        elif not near[i]:
            elsewhere = max(elsewhere, change)
    return float(at), float(elsewhere)


def write(out: Path, data: np.ndarray, summary: dict[str, float]) -> None:
    """``beam.csv`` (time, deflection, the load, the pad's and the
    supports' reactions, cracks) and ``beam.png`` (load against
    deflection)."""
    from fdem.output import write_csv
    from fdem.plot import pyplot, save_axes

    out.mkdir(parents=True, exist_ok=True)
    columns = ["time_s", "deflection_m", "load_N_per_m", "pad_N_per_m", "supports_N_per_m", "cracks"]
    write_csv(out / "beam.csv", columns, data)
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4.5), dpi=110)
    ax.plot(data[:, 1] * 1e3, data[:, 3] / 1e3, lw=0.6, label="reaction at the pad")
    ax.plot(data[:, 1] * 1e3, data[:, 4] / 1e3, lw=0.6, label="support reactions")
    ax.plot(data[:, 1] * 1e3, data[:, 2] / 1e3, color="k", lw=1.2, label="load (their mean)")
    ax.axhline(PETERSSON_PEAK / 1e3, color="grey", ls=":", label="Petersson's tests, peak")
    save_axes(
        fig,
        ax,
        out / "beam.png",
        xlabel="deflection under the pad (mm)",
        ylabel="load (kN per m of thickness)",
        title=f"Notched beam: peak {summary['peak_load'] / 1e3:.2f} kN/m, {int(summary['cracks'])} cracks",
    )


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=float, default=0.01, help="element size at the ligament (m)")
    ap.add_argument("--insert-at", type=float, default=None, help="nodal failure factor of insertion")
    ap.add_argument("--check-every", type=int, default=None, help="steps between fracture checks")
    ap.add_argument("--softening", choices=("bilinear", "linear"), default="bilinear", help="concrete's curve")
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--out", default="beam_output")
    a = ap.parse_args()
    for key, value in main(
        a.size,
        insert_at=a.insert_at,
        check_every=a.check_every,
        softening=a.softening,
        threads=a.threads,
        out=a.out,
    ).items():
        print(f"{key}: {value:.4g}")
