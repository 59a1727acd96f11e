//! What is derived from the connectivity and rebuilt whenever it changes
//! (crack insertion, excavation): node→element lists, the free surfaces,
//! and the pressure facets resolved on them.

use std::collections::BTreeMap;

use fdem_contact::Surface;
use fdem_element::Vec2;
use fdem_mesh::boundary_facets;

use crate::loads::PressureLoad;
use crate::passes::PressureFacet;
use crate::NONE;

/// The free surfaces of the active elements, with the law of each facet
/// from `law_of`.
pub(crate) fn build_surface(
    conn: &[[u32; 3]],
    active: &[bool],
    x_ref: &[Vec2],
    law_of: impl Fn(u32, u32) -> u16,
) -> Surface {
    let ids: Vec<u32> = (0..conn.len() as u32).filter(|&e| active[e as usize]).collect();
    let sub: Vec<[u32; 3]> = ids.iter().map(|&e| conn[e as usize]).collect();
    let facets = boundary_facets(&sub);
    let list: Vec<([u32; 2], u16)> = facets.iter().map(|f| (f.nodes, law_of(f.nodes[0], f.nodes[1]))).collect();
    let apex: Vec<Vec2> =
        facets.iter().map(|f| x_ref[sub[f.element as usize][(f.local as usize + 2) % 3] as usize]).collect();
    Surface::new(x_ref.len(), &list, x_ref, &apex)
}

/// Resolves pressure loads on the surface: each must be a boundary facet
/// (either orientation); it gets the surface's orientation (body on the
/// left). With `strict`, a load off the boundary is an error (at set-up);
/// otherwise it is dropped (its facet was excavated or split).
pub(crate) fn resolve_pressures(
    surface: &Surface,
    loads: &[PressureLoad],
    strict: bool,
) -> Result<Vec<PressureFacet>, String> {
    let by_pair: BTreeMap<(u32, u32), [u32; 2]> =
        surface.facets.iter().map(|f| ((f.nodes[0].min(f.nodes[1]), f.nodes[0].max(f.nodes[1])), f.nodes)).collect();
    let mut out = Vec::with_capacity(loads.len());
    for p in loads {
        let [a, b] = p.nodes;
        match by_pair.get(&(a.min(b), a.max(b))) {
            Some(&nodes) => {
                let bnodes = nodes.map(|n| surface.index_of[n as usize]);
                debug_assert!(bnodes.iter().all(|&b| b != NONE));
                out.push(PressureFacet { nodes, bnodes, pressure: p.pressure, amplitude: p.amplitude });
            }
            None if strict => {
                return Err(format!("pressure facet ({a}, {b}) is not an edge on the boundary of the mesh"));
            }
            None => {}
        }
    }
    Ok(out)
}
