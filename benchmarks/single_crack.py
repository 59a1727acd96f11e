"""Single-crack specimen for issue 33 (4): a 0.2 m square with one central
notch along 112.5 deg, strained uniaxially along 22.5 deg (uniform-strain
velocity on the outer boundary, as in tests/test_fracture.py), so the mode-I
crack should run from the notch tips at 112.5 deg.  Measures the main crack
only (faces connected to the notch), per tip branch and together: the
axis (principal axis of the face midpoints, weighted by length) and the
length-weighted mean deviation of the faces from 112.5 deg. Results and
what they show: docs/fracture.md, "Limits worth knowing" (one crack).
Gf is 2 N/m so that the crack runs to both edges below f_t in the far
field (with 20 N/m it grows only about 2 cm past each tip).

usage: python3 benchmarks/single_crack.py KIND NCELL [key=value ...]
  KIND: right | left | unstructured ; NCELL: cells a side (unstructured: size=side/NCELL)
  keys: gf (N/m, default 2), a (notch half-length, m, 0.03), rate (1/s, 0.1),
        tmax (s), edge_tolerance, min_size, min_quality, crack_tolerance, insert_at,
        check_every (5), ft_far (stop when far-field sigma1 reaches this, Pa)
"""

from __future__ import annotations

import json
import sys
import time

import fdem
import numpy as np

SOFT = dict(E=10e9, nu=0.2, rho=2700.0, c=4e6, phi=35.0, psi=5.0)
SIDE = 0.2
THETA = np.radians(22.5)
N = np.array([np.cos(THETA), np.sin(THETA)])  # load (sigma1) direction
T = np.array([-N[1], N[0]])  # expected crack direction, 112.5 deg
EXPECTED = 112.5


def build(kind, ncell, a, width):
    h = SIDE / ncell
    if kind == "unstructured":
        mesh = fdem.jointed_rectangle(SIDE, SIDE, h, origin=(-SIDE / 2, -SIDE / 2))
    else:
        mesh = fdem.Mesh.rectangle(SIDE, SIDE, ncell, ncell, origin=(-SIDE / 2, -SIDE / 2), pattern=kind)
    c = mesh.centroids()
    s, d = c @ T, c @ N
    notch = (np.abs(s) < a) & (np.abs(d) < width * h)
    keep = np.flatnonzero(~notch)
    tri = mesh.triangles[keep]
    used = np.unique(tri)
    remap = -np.ones(mesh.n_nodes, dtype=np.int64)
    remap[used] = np.arange(len(used))
    pts = mesh.points[used]
    m = fdem.Mesh(pts, remap[tri])
    return m, h, int(notch.sum())


def components(faces, tol):
    """Connected groups of faces (endpoints within tol)."""
    k = len(faces)
    parent = np.arange(k)

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    ends = faces.reshape(-1, 2)  # 2k endpoints, face = idx // 2
    for i in range(len(ends)):
        dist = np.hypot(*(ends[i + 1 :] - ends[i]).T)
        for j in np.flatnonzero(dist < tol) + i + 1:
            ri, rj = find(i // 2), find(j // 2)
            if ri != rj:
                parent[max(ri, rj)] = min(ri, rj)
    roots = np.array([find(i) for i in range(k)])
    return [np.flatnonzero(roots == r) for r in np.unique(roots)]


def axis_of(faces):
    mid = faces.mean(axis=1)
    vec = faces[:, 1] - faces[:, 0]
    length = np.hypot(*vec.T)
    if length.sum() == 0 or len(faces) < 2:
        return dict(axis=float("nan"), length=float(length.sum() / 2), mad=float("nan"), bias=float("nan"))
    cov = np.cov(mid.T, aweights=length)
    w, v = np.linalg.eigh(cov)
    axis = np.degrees(np.arctan2(v[1, -1], v[0, -1])) % 180
    ang = np.degrees(np.arctan2(vec[:, 1], vec[:, 0])) % 180
    dev = (ang - EXPECTED + 90) % 180 - 90
    # fraction of face length along mesh-line directions (0, 45, 90, 135)
    onmesh = np.min(np.abs(ang[:, None] - np.array([0, 45, 90, 135, 180])[None]), axis=1) < 0.5
    return dict(
        axis=float(axis),
        dev=float((axis - EXPECTED + 90) % 180 - 90),
        length=float(length.sum() / 2),  # two faces per crack
        mad=float(np.average(np.abs(dev), weights=length)),
        bias=float(np.average(dev, weights=length)),
        on_mesh_lines=float(length[onmesh].sum() / length.sum()),
        near_expected=float(length[np.abs(dev) < 5].sum() / length.sum()),
        other_split=float(length[(~onmesh) & (np.abs(dev) >= 5)].sum() / length.sum()),
        mean_split_dev=float(np.average(dev[~onmesh], weights=length[~onmesh])) if (~onmesh).any() else float("nan"),
        n=int(len(faces)),
    )


def measure(sim, notch_pts, h):
    facets, laws = sim.surface_facets()
    x = sim.positions()
    f = facets[laws == 1]
    faces = np.stack([x[f[:, 0]], x[f[:, 1]]], axis=1) if len(f) else np.zeros((0, 2, 2))
    if len(faces) == 0:
        return None
    tol = 0.05 * h
    comps = components(faces, tol)
    ends = faces.reshape(-1, 2)
    touches = []
    for c in comps:
        e = ends[np.concatenate([2 * c, 2 * c + 1])]
        dmin = np.min(np.hypot(*(e[:, None, :] - notch_pts[None]).transpose(2, 0, 1)))
        touches.append(dmin < tol)
    main = np.concatenate([c for c, t in zip(comps, touches, strict=True) if t]) if any(touches) else np.array([], int)
    other = [c for c, t in zip(comps, touches, strict=True) if not t]
    mf = faces[main]
    out = dict(
        n_components=len(comps),
        n_touching_notch=int(sum(touches)),
        secondary=[
            dict(
                n=len(c),
                length=float(np.hypot(*(faces[c, 1] - faces[c, 0]).T).sum() / 2),
                centre=[round(v, 4) for v in faces[c].reshape(-1, 2).mean(0).tolist()],
            )
            for c in other
        ],
    )
    if len(mf):
        mid = mf.mean(axis=1)
        s = mid @ T
        out["reach"] = [float(s.min()), float(s.max())]
        out["all"] = axis_of(mf)
        out["plus"] = axis_of(mf[s > 0])
        out["minus"] = axis_of(mf[s < 0])
        inner = np.abs(s) < 0.07
        out["inner"] = axis_of(mf[inner])
        # lateral offset of the main crack from the notch line (m)
        out["offset_max"] = float(np.max(np.abs(mid @ N)))
    return out


def main():
    kind, ncell = sys.argv[1], int(sys.argv[2])
    kw = dict(a.split("=") for a in sys.argv[3:])
    gf = float(kw.pop("gf", 2.0))
    a = float(kw.pop("a", 0.03))
    rate = float(kw.pop("rate", 0.1))
    width = float(kw.pop("width", 0.75))
    check_every = int(kw.pop("check_every", 5))
    ft_far = float(kw.pop("ft_far", 0.9e6))
    frac = {k: float(v) for k, v in kw.items()}
    mesh, h, removed = build(kind, ncell, a, width)
    pts = mesh.points
    outer = np.flatnonzero(np.max(np.abs(pts), axis=1) > SIDE / 2 - 1e-9)
    bnodes = np.unique(mesh.boundary_facets())
    notch_nodes = np.setdiff1d(bnodes, outer)
    material = dict(**{**SOFT, "c": 8e6}, Gf=gf)
    model = fdem.Model(mesh, material=fdem.MohrCoulombRankine(**material, ft=1.0e6))
    tr = 1e-4
    model.prescribe_velocity(
        outer,
        vx=lambda x, y: rate * (x * N[0] + y * N[1]) * N[0],
        vy=lambda x, y: rate * (x * N[0] + y * N[1]) * N[1],
        amplitude=fdem.Amplitude.ramp(tr),
    )
    model.contact(fdem.Interface(friction=30, damping=0.5)).fracture(check_every=check_every, **frac)
    sim = fdem.Simulation(model, stiffness_damping=1e-6, threads=1)
    E, nu = SOFT["E"], SOFT["nu"]
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    # stop when the far field reaches ft_far (uniform-strain sigma_nn = (lam+2mu) eps)
    eps_stop = ft_far / (lam + 2 * mu)
    t_stop = eps_stop / rate + tr / 2
    t_stop = float(kw.get("tmax", t_stop))
    t0 = time.time()
    t, dtc = 0.0, 1e-5
    first = None
    while t < t_stop:
        t = min(t + dtc, t_stop)
        sim.run(until=t, progress=False)
        if sim.insertions and first is None:
            strain = rate * (t - tr / 2) if t > tr else rate * t * t / (2 * tr)
            first = dict(t=t, sigma_far=float((lam + 2 * mu) * strain))
        if sim.insertions:
            m = measure(sim, sim.positions()[notch_nodes], h)
            if m and "reach" in m and m["reach"][0] < -0.09 and m["reach"][1] > 0.09:
                break
    wall = time.time() - t0
    strain = rate * (t - tr / 2)
    res = dict(
        kind=kind,
        ncell=ncell,
        h=h,
        elements=mesh.n_elements,
        notch_removed=removed,
        gf=gf,
        a=a,
        rate=rate,
        frac=frac,
        t_end=t,
        sigma_far_end=float((lam + 2 * mu) * strain),
        first=first,
        insertions=sim.insertions,
        wall=round(wall, 1),
        m=measure(sim, sim.positions()[notch_nodes], h),
    )
    print(json.dumps(res))


if __name__ == "__main__":
    main()
