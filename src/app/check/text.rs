//! The text `tensolve check` prints of its report: the structure, the model, the run and
//! each solver's set-up.

use super::{CheckReport, LatinReport, LENGTH_WARNING, STIFFNESS_RATIO_WARNING};
use crate::output::alpha_label;
use std::fmt;

impl fmt::Display for CheckReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.write_structure(f)?;
        self.write_model(f)?;
        self.write_run(f)?;
        if !self.stiffness_regular {
            return Ok(());
        }
        self.write_set_up(f)
    }
}

impl CheckReport {
    /// The structure: its size, supports, members and their magnitudes (with the unit-slip
    /// warnings).
    fn write_structure(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = &self.model;
        writeln!(f, "case            {}", m.case.display())?;
        match (m.modules, m.module) {
            (Some([nx, ny]), Some(module)) => {
                writeln!(f, "grid            {nx} x {ny} modules ({module:?})")?
            }
            _ => writeln!(f, "structure       general (node and member tables)")?,
        }
        writeln!(f, "nodes           {}", m.nodes)?;
        writeln!(f, "dofs            {}", 3 * m.nodes)?;
        writeln!(f, "free dofs       {}", m.free_dofs)?;
        writeln!(
            f,
            "held nodes      {} (all three components), {} on some components; {} \
             prescribed non-zero displacement(s)",
            m.clamped_nodes, m.partly_held_nodes, m.prescribed_components
        )?;
        if m.held_load_components > 0 {
            writeln!(
                f,
                "held loads      {} load component(s) (load.point, self-weight) sit on held \
                 components: they take no part in the solve and go straight to the reactions \
                 (reactions/)",
                m.held_load_components
            )?;
        }
        writeln!(
            f,
            "cables          {} ({})",
            m.cables,
            if m.unilateral {
                "unilateral"
            } else {
                "bilateral"
            }
        )?;
        writeln!(f, "bars            {}", m.bars)?;
        let [x, y, z] = m.bounding_box;
        writeln!(
            f,
            "bounding box    x {:.4e} .. {:.4e}, y {:.4e} .. {:.4e}, z {:.4e} .. {:.4e} m",
            x[0], x[1], y[0], y[1], z[0], z[1]
        )?;
        writeln!(
            f,
            "member lengths  {:.4e} .. {:.4e} m",
            m.lengths[0], m.lengths[1]
        )?;
        writeln!(
            f,
            "member E·S      {:.4e} .. {:.4e} N",
            m.axial_rigidity[0], m.axial_rigidity[1]
        )?;
        let ratio = m.stiffness_ratio();
        if ratio > STIFFNESS_RATIO_WARNING {
            writeln!(
                f,
                "  warning: the members' stiffness E·S/ℓ spans a ratio of {ratio:.1e} (beyond \
                 {STIFFNESS_RATIO_WARNING:.0e}): is E given in Pa on every member (not GPa), S in m²?"
            )?;
        }
        if let Some((id, strain)) = m.prestress_strain {
            writeln!(
                f,
                "  warning: {}",
                crate::model::unit_slip_sentence(id, strain)
            )?;
        }
        if let Some(spread) = m.flat_form {
            writeln!(
                f,
                "  warning: {}",
                crate::app::design::flat_form_sentence(spread)
            )?;
        }
        if let Some((id, section, diameter, length)) = m.thick_member {
            writeln!(
                f,
                "  warning: member {id} is too stocky for a member of a tension structure: its \
                 section {section:.4e} m² has the diameter {diameter:.3e} m of a disc, for a \
                 length of {length:.3e} m: \
                 are the sections in m² (not mm² or cm²)?"
            )?;
        }
        if m.lengths[1] > LENGTH_WARNING {
            writeln!(
                f,
                "  warning: a member is {:.3e} m long (beyond {LENGTH_WARNING:.0e} m): are the \
                 coordinates in m (not mm)?",
                m.lengths[1]
            )?;
        }
        Ok(())
    }

    /// The model, the prestress's balance, and the equilibrium matrix's counts (with the
    /// mechanisms' prestress stability).
    fn write_model(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = &self.model;
        match &m.auto {
            Some(start) => writeln!(
                f,
                "model           geometry = auto, starts {} ({}): {}",
                m.geometry.name(),
                m.geometry.description(),
                start.reason.trim_start_matches("auto: ")
            )?,
            None => writeln!(
                f,
                "model           geometry = {} ({})",
                m.geometry.name(),
                m.geometry.description()
            )?,
        }
        writeln!(
            f,
            "max |B^T t0|    {:.3e} N ({:.1e} of the prestress scale)",
            m.prestress_imbalance,
            if m.prestress > 0.0 {
                m.prestress_imbalance / m.prestress
            } else {
                0.0
            }
        )?;
        writeln!(f, "  at free dofs  {:.3e} N", m.free_prestress_imbalance)?;
        let c = &m.counts;
        if m.mechanisms_at_least {
            writeln!(
                f,
                "equilibrium     A = B^T is {} x {}, rank at most {}: at least {} self-stress \
                 state(s), at least {} mechanism(s) (rigid motions included; counted up to {}, \
                 every one above {} free dofs)",
                c.free_dofs,
                c.members,
                c.rank,
                c.self_stress_states,
                c.mechanisms,
                crate::linalg::ZERO_MODES_COUNTED,
                crate::structure::DENSE_LIMIT
            )?;
        } else {
            writeln!(
                f,
                "equilibrium     A = B^T is {} x {}, rank {}: {} self-stress state(s), {} mechanism(s) (rigid motions included)",
                c.free_dofs, c.members, c.rank, c.self_stress_states, c.mechanisms
            )?;
        }
        if c.mechanisms > 0 {
            match &m.stability {
                Some(st) if st.stable() && matches!(m.geometric_regular, Some(Err(_))) => writeln!(
                    f,
                    "                prestress-stable in its {} mechanism(s) (smallest \
                         eigenvalue of M^T K_G M {:.3e} N/m), but K + K_G(t0) is not positive \
                         definite, so no model solves it: {}",
                    st.mechanisms,
                    st.smallest().unwrap_or(0.0),
                    match &m.geometric_regular {
                        Some(Err(reason)) => reason.as_str(),
                        _ => "",
                    }
                )?,
                Some(st) if st.stable() => writeln!(
                    f,
                    "                prestress-stable: the prestress stiffens all {} mechanism(s) \
                     (smallest eigenvalue of M^T K_G M {:.3e} N/m): solvable with \
                     model.geometry = prestress or large{}",
                    st.mechanisms,
                    st.smallest().unwrap_or(0.0),
                    if m.geometry.has_geometric_stiffness() {
                        ""
                    } else {
                        " (refused with the linear model, which has no geometric stiffness)"
                    }
                )?,
                Some(st) => {
                    writeln!(
                        f,
                        "                not prestress-stable: {} of {} mechanism(s) not stiffened \
                         by the prestress (refused by every model); hold more components \
                         (`supports.fix`), add members or change the prestress:",
                        st.unstiffened().count(),
                        st.mechanisms
                    )?;
                    for mode in &m.unstiffened_modes {
                        writeln!(f, "                  {mode}")?;
                    }
                }
                None => writeln!(
                    f,
                    "                a mechanism: refused with model.geometry = linear; prestress \
                     stability is tested here up to {} free dofs (with geometric stiffness, run \
                     factorizes K + K_G(t0) and refuses it when not positive definite)",
                    crate::structure::DENSE_LIMIT
                )?,
            }
        }
        Ok(())
    }

    /// What a run would do: the load factors, the solvers, the memory it needs.
    fn write_run(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = &self.model;
        let alphas: Vec<String> = m.alphas.iter().map(|&a| alpha_label(a)).collect();
        writeln!(f, "load factors    {}", alphas.join(", "))?;
        let (cases, combinations) = &m.combinations;
        if !cases.is_empty() {
            writeln!(f, "load cases      {}", cases.join(", "))?;
        }
        if !combinations.is_empty() {
            writeln!(
                f,
                "combinations    {}: each solved on its own (cables go slack: never superposed), \
                 into combinations/<name>/, with envelope/ over them",
                combinations.join(", ")
            )?;
        }
        if !m.stages.is_empty() {
            writeln!(
                f,
                "stages          {}: solved in order, each from the last, into stages/<name>/",
                m.stages.join(", ")
            )?;
        }
        let methods: Vec<&str> = m.methods.iter().map(|m| m.name()).collect();
        writeln!(f, "solvers         {}", methods.join(", "))?;
        if let Some((linear, [sx, sy])) = m.newton_linear {
            use crate::solvers::newton::LinearSolve;
            let why = match linear {
                LinearSolve::Direct => "a sparse factor of each Hessian (the default at every \
                                        size measured: docs/performance.md)"
                    .to_string(),
                LinearSolve::Krylov => format!(
                    "PCG with a two-level Schwarz preconditioner on the {sx} x {sy} partition \
                     (GenEO coarse space); slower than direct at every size measured so far \
                     (2.2-2.6x at 256 x 256 modules, 1.24x at 512 x 512 for the whole run), in 27-30 % \
                     less memory from 256 x 256 on (docs/performance.md)"
                ),
            };
            writeln!(f, "  newton solve  {}: {why}", linear.name())?;
        }
        writeln!(f, "memory (run)    {}", self.memory)?;
        match &self.available {
            Some(a) => writeln!(f, "  available     {a}")?,
            None => writeln!(f, "  available     unknown (no limit readable)")?,
        }
        Ok(())
    }

    /// The taut stiffness, and each LATIN solver's partition as set up.
    fn write_set_up(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = &self.model;
        writeln!(
            f,
            "stiffness       positive definite with every cable taut{}",
            if m.geometry.has_geometric_stiffness() {
                " (K + K_G(t0), the prestress's geometric stiffness included)"
            } else {
                ""
            }
        )?;
        for LatinReport {
            method,
            settings,
            partition: r,
            partition_origin,
        } in &self.latin
        {
            let [sx, sy] = settings.subdomains;
            writeln!(f, "{}:", method.name())?;
            writeln!(
                f,
                "  substructures {} ({sx} x {sy}: {partition_origin}), largest {} free dofs",
                r.substructures, r.max_substructure_dofs
            )?;
            writeln!(
                f,
                "  interfaces    {} ({} strong, {} weak, {} dropped; weak = {:?})",
                r.interfaces,
                r.strong_interfaces,
                r.weak_interfaces,
                r.dropped_interfaces,
                settings.weak
            )?;
            let degree_origin = match settings.macro_degree {
                Some(_) => "solver.macro_degree",
                None => "default round(H/4), 1 to 16, at most what the partition takes",
            };
            match r.strong_interfaces {
                0 => writeln!(f, "  macro dofs    {}", r.macro_dofs)?,
                _ => writeln!(
                    f,
                    "  macro dofs    {} (degree {} on strong interfaces: {degree_origin})",
                    r.macro_dofs, r.macro_degree
                )?,
            }
            writeln!(f, "  kernel cols   {}", r.kernel_columns)?;
            let (unknowns, entries) = r.macro_system;
            if unknowns > 0 {
                let subtrees = match r.macro_subtrees {
                    1 => "whole".to_string(),
                    k => format!("in {k} subtrees of substructures side by side"),
                };
                writeln!(
                    f,
                    "  macro system  {unknowns} unknowns, its LDLt factor {entries} entries \
                     ({:.1} MB, {subtrees}; factorised and solved on every MPI rank)",
                    8.0 * entries as f64 / 1e6
                )?;
            }
            let origin = if settings.dm.is_some() {
                "solver.dm".to_string()
            } else {
                format!("default {} p k/sqrt(H)", crate::solvers::latin::DM_FACTOR)
            };
            writeln!(f, "  d_m           {:.4e} N/m ({origin})", r.dm)?;
        }
        Ok(())
    }
}
