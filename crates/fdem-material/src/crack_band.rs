//! The crack band of an element (paper B.5, DESIGN §4.3): how its width
//! `h_c` is measured, and the element shape the law measures it on.

/// How the crack-band width `h_c` of an element is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum CrackBand {
    /// The element's width along σ1 when it first reaches `f_t`
    /// (Oliver 1989); dissipates `G_f` per unit crack length within about 1%
    /// on unstructured meshes. The default.
    Oliver,
    /// The paper's `√(4A/π)` (B.5a), blind to the crack direction: about 20%
    /// too much dissipation for a band one element wide.
    Equivalent,
}

/// The shape an element gives the law for its crack band: its two edge
/// vectors from vertex 0 in the co-rotational (reference-oriented) frame (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    /// `X1 − X0`.
    pub e1: [f64; 2],
    /// `X2 − X0`.
    pub e2: [f64; 2],
}

impl Geometry {
    /// Width of the triangle measured along the direction at `angle` (m).
    pub fn width_along(&self, angle: f64) -> f64 {
        let (c, s) = (angle.cos(), angle.sin());
        let p1 = self.e1[0] * c + self.e1[1] * s;
        let p2 = self.e2[0] * c + self.e2[1] * s;
        0.0f64.max(p1).max(p2) - 0.0f64.min(p1).min(p2)
    }

    /// Area (m²).
    pub fn area(&self) -> f64 {
        0.5 * (self.e1[0] * self.e2[1] - self.e1[1] * self.e2[0]).abs()
    }

    /// Longest edge (m): the largest width over all directions.
    pub fn diameter(&self) -> f64 {
        let d = [self.e2[0] - self.e1[0], self.e2[1] - self.e1[1]];
        self.e1[0].hypot(self.e1[1]).max(self.e2[0].hypot(self.e2[1])).max(d[0].hypot(d[1]))
    }

    /// Diameter of the circle of the same area, `√(4A/π)` (m).
    pub fn equivalent_diameter(&self) -> f64 {
        (4.0 * self.area() / std::f64::consts::PI).sqrt()
    }
}
