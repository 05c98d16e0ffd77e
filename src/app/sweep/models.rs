//! The model of each α's rows (`model.geometry`): the one the case pins, or under `auto` the
//! one [`AutoModel`] chooses; on `auto`'s move to `large`, the solvers and the reference set up
//! again on it.

use super::{set_up_all, PathStart, RunError, RunEvent, Sweep};
use crate::app::auto::{large_case, AutoModel, RowModel};
use crate::app::reference::ReferenceSource;
use crate::app::setup::{AnswerChecks, Prepared};
use crate::case::Case;
use crate::labels::alpha_label;
use crate::solvers::Method;
use std::cell::OnceCell;

/// The model of the rows along a sweep.
pub(super) struct Models<'s> {
    /// The model of the rows being solved, and why.
    pub(super) row: RowModel,
    /// `auto` while `linear`: the choice at each α. `None` for a pinned model, and once `auto`
    /// is `large`.
    auto: Option<AutoModel<'s>>,
    /// `large` prepared, once `auto` moves to it.
    large: &'s OnceCell<Prepared>,
    pub(super) case: &'s Case,
    methods: Vec<Method>,
    /// The α where `auto` moved to `large`, and what it measured there.
    since: Option<(f64, String)>,
}

impl<'s> Models<'s> {
    /// The models of a sweep of `case` by `methods` that starts with `start` on `prepared`;
    /// `large`, where `auto` keeps `large`'s preparation once it moves to it.
    pub(super) fn new(
        case: &'s Case,
        methods: &[Method],
        start: RowModel,
        prepared: &'s Prepared,
        large: &'s OnceCell<Prepared>,
    ) -> Result<Models<'s>, RunError> {
        let auto = AutoModel::starting(case, &start, prepared)?;
        Ok(Models {
            row: start,
            auto,
            large,
            case,
            methods: methods.to_vec(),
            since: None,
        })
    }
}

impl Sweep<'_> {
    /// Step 6a: the model of the rows at `alpha`. Under `auto` while `linear`, newton's linear
    /// answer is measured against `large` ([`AutoModel::choose`]); past the tolerance, this
    /// α and every later one are solved with `large`.
    pub(super) fn choose_model(
        &mut self,
        alpha: f64,
        events: &mut dyn FnMut(RunEvent<'_>),
    ) -> Result<(), RunError> {
        if let Some((from, measured)) = &self.models.since {
            self.models.row.reason = format!(
                "auto: large since alpha = {}, {measured}",
                alpha_label(*from)
            );
            return Ok(());
        }
        let Some(auto) = self.models.auto.as_mut() else {
            return Ok(());
        };
        events(RunEvent::Stage(&format!(
            "auto: linear's distance to large at alpha = {}",
            alpha_label(alpha)
        )));
        let load = self.prepared.model.load(alpha);
        let chosen = auto.choose(alpha, &load);
        if chosen.moves_to_large() {
            self.models.auto = None;
            self.move_to_large(events)?;
            self.models.since = Some((alpha, chosen.measured.clone()));
        }
        self.models.row = chosen.row;
        Ok(())
    }

    /// `auto`'s move to `large`: the structure prepared under it (K + K_G(t0) factorized),
    /// every solver and the reference set up again on it, their warm starts and load paths
    /// begun afresh (the path from the prestressed state).
    fn move_to_large(&mut self, events: &mut dyn FnMut(RunEvent<'_>)) -> Result<(), RunError> {
        events(RunEvent::Stage("auto: preparing the structure under large"));
        let case = large_case(self.models.case);
        let prepared = super::on_every_rank(
            self.exchange,
            self.prepared.under(case.model).map_err(RunError::from),
        )?;
        let prepared = self.models.large.get_or_init(|| prepared);
        // The linear solvers go before the large ones are set up.
        self.solvers.clear();
        self.solvers = set_up_all(&case, &self.models.methods, prepared, self.exchange, events)?;
        self.reference = ReferenceSource::new(&case, &self.solvers, prepared)?;
        self.prepared = prepared;
        self.previous = vec![None; self.solvers.len()];
        self.paths = vec![PathStart::default(); self.solvers.len()];
        self.checks = AnswerChecks::of(&case);
        Ok(())
    }
}
