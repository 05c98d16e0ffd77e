//! The homogenised behaviour of the substructures, what a micro-macro solve leaves besides its
//! answer: each substructure's flexibility on its interfaces' macro fields.

/// One macro dof of a substructure: a column of one of its interfaces' macro bases.
#[derive(Debug, Clone)]
pub struct MacroDof {
    /// The interface (numbered as `check` counts them).
    pub interface: usize,
    /// The substructure on the other side.
    pub neighbour: usize,
    /// The macro field, with its axes.
    pub field: String,
    /// Centroid of the interface, m.
    pub centroid: [f64; 3],
}

/// The paper's "second-hand product" of one substructure (its conclusion): its homogenised
/// flexibility `L_E = K⁺_E − I/d_m` on its macro dofs, with l as set up.
#[derive(Debug, Clone)]
pub struct Homogenised {
    /// The substructure, row by row of the partition.
    pub substructure: usize,
    /// Its macro dofs, in the order of `flexibility`'s rows and columns.
    pub dofs: Vec<MacroDof>,
    /// L_E, m/N.
    pub flexibility: nalgebra::DMatrix<f64>,
}
