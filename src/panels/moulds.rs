//! Fewest moulds: panels of one radius share a mould (a sphere looks the same everywhere, and a
//! panel can be turned over), so the moulds a result needs are the radii its panels can share
//! within a fit tolerance δ.
//!
//! **Fit.** A mould of curvature κ is placed tangent to the panel at its centre c (the point of
//! the panel's sphere nearest the mean of its boundary samples), with the panel's normal n there.
//! A boundary point x, with h = ⟨x − c, n⟩ and q = |x − c|², lies at distance
//! |κq − 2h| / (1 + √(κ²q − 2κh + 1)) from it, and within δ exactly for
//! κ ∈ [2(h − δ)/(q − δ²), 2(h + δ)/(q − δ²)] (any κ when q ≤ δ²). The panel fits the mould when
//! all its boundary points do: an interval of κ around the panel's own curvature, and, since a
//! panel can be turned over, an interval of mould curvatures |κ|, a plane (0) included.
//!
//! **Fewest moulds.** The fewest values hitting every interval: sorted by right end, each
//! interval not yet hit takes its right end (the classic greedy, optimal). Each mould then takes
//! the middle of the intersection of its panels' intervals, which every one of them fits (an
//! intersection unbounded above, of panels within δ of their centre: their mean curvature,
//! clamped into it).

use crate::params::{percent_encode, LinkFields, LinkReader, LinkWriter, ParamRange};
use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::panel::Panel;
use crate::progress::{Cancelled, Progress};
use crate::units::{Length, Units};

/// Boundary samples per arc of a panel (the arcs' own points, corners included).
pub const SAMPLES_PER_ARC: usize = 16;

/// What fitting needs of each panel: its own curvature and its boundary samples (h, q) in the
/// frame of its centre.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MouldFits {
    /// Signed curvature of each panel's sphere along its normal at the centre (0: a plane).
    pub curvature: Vec<f64>,
    /// Each panel's centre c, where its mould is placed tangent, and its unit normal there.
    pub centres: Vec<DVec3>,
    pub normals: Vec<DVec3>,
    /// `(h, q)` of the boundary samples; panel i's are `samples[offsets[i]..offsets[i + 1]]`.
    samples: Vec<[f64; 2]>,
    offsets: Vec<usize>,
}

/// One mould: its curvature (0 for a flat mould) and the panels cut from it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mould {
    pub curvature: f64,
    /// 1/curvature; None for a flat mould.
    pub radius: Option<f64>,
    pub panels: usize,
    /// The largest distance of a panel's boundary from this mould.
    pub max_deviation: f64,
}

/// The moulds of a result at one tolerance: each panel's mould and fit deviation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MouldAssignment {
    pub tolerance: f64,
    /// By increasing curvature.
    pub moulds: Vec<Mould>,
    /// Index into `moulds` per panel.
    pub panel_mould: Vec<u32>,
    /// Each panel's largest boundary distance from its mould (≤ `tolerance`).
    pub panel_deviation: Vec<f64>,
}

impl MouldFits {
    /// The fit data of `panels`.
    pub fn of(panels: &[Panel]) -> Self {
        let mut fits = MouldFits { offsets: vec![0], ..Default::default() };
        for p in panels {
            let points: Vec<DVec3> = p.arcs.iter().flat_map(|a| a.sample(SAMPLES_PER_ARC)).collect();
            let mean = points.iter().copied().sum::<DVec3>() / points.len().max(1) as f64;
            let s = p.sphere;
            let c = s.closest_point(mean);
            let n = s.normal_at(c).try_normalize().unwrap_or(DVec3::Z);
            // normal_at is unit on a normalized sphere and points to the centre: c + n/(2a).
            let scale = s.normal_at(c).length();
            fits.curvature.push(if scale > 0.0 { 2.0 * s.a / scale } else { 0.0 });
            fits.centres.push(c);
            fits.normals.push(n);
            fits.samples.extend(points.iter().map(|&x| [(x - c).dot(n), (x - c).length_squared()]));
            fits.offsets.push(fits.samples.len());
        }
        fits
    }

    pub fn len(&self) -> usize {
        self.curvature.len()
    }

    pub fn is_empty(&self) -> bool {
        self.curvature.is_empty()
    }

    fn samples(&self, i: usize) -> &[[f64; 2]] {
        &self.samples[self.offsets[i]..self.offsets[i + 1]]
    }

    /// The signed curvatures κ (along the panel's normal) of the moulds panel `i` fits within
    /// `tolerance`: an interval containing its own curvature.
    pub fn signed_interval(&self, i: usize, tolerance: f64) -> [f64; 2] {
        let d = tolerance.max(0.0);
        let mut range = [f64::NEG_INFINITY, f64::INFINITY];
        for &[h, q] in self.samples(i) {
            let denominator = q - d * d;
            if denominator > 0.0 {
                range[0] = range[0].max(2.0 * (h - d) / denominator);
                range[1] = range[1].min(2.0 * (h + d) / denominator);
            }
        }
        // Rounding can leave the own curvature a hair outside at δ = 0.
        let own = self.curvature[i];
        [range[0].min(own), range[1].max(own)]
    }

    /// The mould curvatures |κ| panel `i` fits within `tolerance`, turned over or not.
    pub fn interval(&self, i: usize, tolerance: f64) -> [f64; 2] {
        let [lo, hi] = self.signed_interval(i, tolerance);
        if lo <= 0.0 && hi >= 0.0 {
            [0.0, (-lo).max(hi)]
        } else if lo > 0.0 {
            [lo, hi]
        } else {
            [-hi, -lo]
        }
    }

    /// The largest distance of panel `i`'s boundary samples from a mould of curvature
    /// `magnitude`, the better of the two ways up.
    pub fn deviation(&self, i: usize, magnitude: f64) -> f64 {
        let way = |k: f64| self.samples(i).iter().map(|&[h, q]| tangent_sphere_distance(k, h, q)).fold(0.0, f64::max);
        way(magnitude).min(way(-magnitude))
    }

    /// The fewest moulds within `tolerance`, each panel's mould and deviation.
    pub fn assign(&self, tolerance: f64) -> MouldAssignment {
        let intervals: Vec<[f64; 2]> = (0..self.len()).map(|i| self.interval(i, tolerance)).collect();
        let stabs = fewest_stabbing_values(&intervals);
        // Each panel to the mould nearest its own |κ| among those it fits.
        let mut panel_mould = Vec::with_capacity(intervals.len());
        let mut common: Vec<[f64; 2]> = vec![[f64::NEG_INFINITY, f64::INFINITY]; stabs.len()];
        let mut own_sum = vec![(0.0, 0usize); stabs.len()];
        for (i, &[lo, hi]) in intervals.iter().enumerate() {
            let first = stabs.partition_point(|&s| s < lo);
            let last = stabs.partition_point(|&s| s <= hi);
            let own = self.curvature[i].abs();
            let j = (first..last.max(first + 1).min(stabs.len()))
                .min_by(|&a, &b| (stabs[a] - own).abs().total_cmp(&(stabs[b] - own).abs()))
                .unwrap_or(first.min(stabs.len().saturating_sub(1)));
            common[j] = [common[j][0].max(lo), common[j][1].min(hi)];
            own_sum[j] = (own_sum[j].0 + own, own_sum[j].1 + 1);
            panel_mould.push(j as u32);
        }
        let value = |(&[lo, hi], &s): (&[f64; 2], &f64), &(sum, n): &(f64, usize)| match (lo <= hi, hi.is_finite()) {
            (true, true) => 0.5 * (lo + hi),
            // Panels within δ of their centre fit every steeper mould: their mean curvature, as
            // near as the others allow.
            (true, false) => (sum / n.max(1) as f64).clamp(lo, f64::MAX),
            (false, _) => s,
        };
        let values: Vec<f64> = common.iter().zip(&stabs).zip(&own_sum).map(|(c, o)| value(c, o)).collect();
        self.cut_from(tolerance, &values, panel_mould)
    }

    /// Each panel cut from the mould `panel_mould` of `curvatures`, its deviation measured.
    fn cut_from(&self, tolerance: f64, curvatures: &[f64], panel_mould: Vec<u32>) -> MouldAssignment {
        let mut moulds: Vec<Mould> =
            curvatures.iter().map(|&k| Mould { curvature: k, radius: (k > 0.0).then(|| 1.0 / k), panels: 0, max_deviation: 0.0 }).collect();
        let panel_deviation: Vec<f64> = panel_mould
            .iter()
            .enumerate()
            .map(|(i, &j)| {
                let m = &mut moulds[j as usize];
                let d = self.deviation(i, m.curvature);
                m.panels += 1;
                m.max_deviation = m.max_deviation.max(d);
                d
            })
            .collect();
        MouldAssignment { tolerance, moulds, panel_mould, panel_deviation }
    }

    /// These panels on the moulds of `given` (the same panel order), their deviations measured
    /// again: the moulds a method snapped its panels to.
    pub fn on_moulds(&self, given: &MouldAssignment) -> MouldAssignment {
        let curvatures: Vec<f64> = given.moulds.iter().map(|m| m.curvature).collect();
        self.cut_from(given.tolerance, &curvatures, given.panel_mould.clone())
    }

    /// Whether panel `i`'s sphere has exactly the radius of a mould of curvature `magnitude`:
    /// the radii within [`SNAPPED`] × `diagonal` (a flat mould: the panel's radius at least
    /// `diagonal` / [`SNAPPED`]).
    pub fn has_mould_radius(&self, i: usize, magnitude: f64, diagonal: f64) -> bool {
        match self.radius_miss(i, magnitude) {
            Some(miss) => miss <= SNAPPED * diagonal,
            // One of them flat: the other too, to a radius of diagonal / SNAPPED.
            None => self.curvature[i].abs().max(magnitude) * diagonal <= SNAPPED,
        }
    }

    /// |r − R|: panel `i`'s radius against a mould of curvature `magnitude`; None when either
    /// is flat.
    pub fn radius_miss(&self, i: usize, magnitude: f64) -> Option<f64> {
        let own = self.curvature[i].abs();
        (own > 0.0 && magnitude > 0.0).then(|| (1.0 / own - 1.0 / magnitude).abs())
    }

    /// The fewest moulds within `tolerance` (the count of [`Self::assign`], without assigning).
    pub fn count(&self, tolerance: f64) -> usize {
        let intervals: Vec<[f64; 2]> = (0..self.len()).map(|i| self.interval(i, tolerance)).collect();
        fewest_stabbing_values(&intervals).len()
    }

    /// The smallest tolerance for which `moulds` moulds suffice (bisection on the count, which
    /// never grows with the tolerance), to a relative 1e-6; `upper` is a tolerance known to need
    /// one mould at most (e.g. the bounding-box diagonal). 0 when no panel needs to move.
    pub fn tolerance_for_count(&self, moulds: usize, upper: f64) -> f64 {
        let moulds = moulds.max(1);
        if self.count(0.0) <= moulds {
            return 0.0;
        }
        let mut hi = upper.max(f64::MIN_POSITIVE);
        while self.count(hi) > moulds && hi < f64::MAX / 4.0 {
            hi *= 2.0;
        }
        let mut lo = 0.0;
        while hi - lo > 1e-6 * hi {
            let mid = 0.5 * (lo + hi);
            if self.count(mid) <= moulds {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    }

    /// Moulds against tolerance from 1/30 to 30 times `tolerance` (1e-5 to 1e-2 of `diag` when
    /// that is 0): (tolerance, count) pairs, ascending.
    pub fn against_tolerance(&self, tolerance: f64, diag: f64) -> Vec<(f64, usize)> {
        let (lo, hi) = if tolerance > 0.0 { (tolerance / 30.0, tolerance * 30.0) } else { (1e-5 * diag, 1e-2 * diag) };
        let steps = 24;
        let tolerances: Vec<f64> = (0..=steps).map(|k| lo * (hi / lo).powf(k as f64 / steps as f64)).collect();
        tolerances.iter().copied().zip(self.counts(&tolerances)).collect()
    }

    /// Moulds against tolerance: the count at each of `tolerances`.
    pub fn counts(&self, tolerances: &[f64]) -> Vec<usize> {
        tolerances.iter().map(|&t| self.count(t)).collect()
    }
}

/// A panel cut from its mould with no deviation has the mould's radius to this fraction of
/// the diagonal.
pub const SNAPPED: f64 = 1e-9;

/// Why a panel's sphere does not have its mould's radius exactly.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SnapLimit {
    /// The method fixes the sphere by the panel's vertices (SQ: four; ST with support
    /// structure: three and Ω), so a new radius would move them.
    FixedByVertices,
    /// The mould's radius is below the circumradius of the panel's corners.
    MouldBelowCircumradius,
    /// Snapping would break the method's kink or distance targets.
    MethodTargets,
    /// Snapping was not asked for.
    NotAsked,
    /// Snapped, but measured off its mould's radius.
    Missed,
}

impl SnapLimit {
    /// In words, for the app and the CLI.
    pub fn describe(self) -> &'static str {
        match self {
            SnapLimit::FixedByVertices => "the sphere is fixed by the panel's vertices",
            SnapLimit::MouldBelowCircumradius => "the mould is smaller than the panel's corners",
            SnapLimit::MethodTargets => "snapping would break the method's targets",
            SnapLimit::NotAsked => "not asked for",
            SnapLimit::Missed => "snapped but off the mould's radius",
        }
    }
}

/// The moulds a method snapped its panels to, and per panel why it could not (None: snapped).
#[derive(Clone, Debug, PartialEq)]
pub struct MouldSnap {
    pub moulds: MouldAssignment,
    pub limits: Vec<Option<SnapLimit>>,
}

/// The figures every method's round toward fewer moulds has: the moulds at δ of its moved panels,
/// their largest distance to the reference (relative to the diagonal), and whether it was kept.
pub trait MouldRoundFigures {
    fn moulds(&self) -> usize;
    fn distance_to_reference(&self) -> f64;
    fn kept(&self) -> bool;
}

/// What a method's rounds toward fewer moulds ([`fewer_moulds`]) did.
#[derive(Clone, Debug)]
pub struct MouldOutcome<Round> {
    /// The moulds the kept panels were snapped to, or why none was.
    pub snap: Result<MouldSnap, SnapLimit>,
    pub rounds: Vec<Round>,
    /// Moulds at δ before the rounds, and the fits of the panels then.
    pub before: usize,
    pub fits_before: MouldFits,
    /// The largest distance to the reference a round may reach (relative).
    pub distance_limit: f64,
}

impl<Round: Clone> MouldOutcome<Round> {
    /// The rounds as a method's report section carries them.
    pub fn section(outcome: Option<&Self>) -> MouldRoundsSection<Round> {
        MouldRoundsSection {
            mould_rounds: outcome.map(|o| o.rounds.clone()).unwrap_or_default(),
            moulds_before: outcome.map(|o| o.before),
            moulds_distance_limit: outcome.map(|o| o.distance_limit),
        }
    }
}

/// The rounds toward fewer moulds (`optimize_moulds`) in a method's report section, the moulds at
/// δ before them, and the distance limit the rounds were held to.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MouldRoundsSection<Round> {
    #[serde(default = "Vec::new", skip_serializing_if = "Vec::is_empty")]
    pub mould_rounds: Vec<Round>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub moulds_before: Option<usize>,
    /// Relative to the diagonal.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub moulds_distance_limit: Option<f64>,
}

impl<Round> Default for MouldRoundsSection<Round> {
    fn default() -> Self {
        Self { mould_rounds: Vec::new(), moulds_before: None, moulds_distance_limit: None }
    }
}

impl<Round: MouldRoundFigures> MouldRoundsSection<Round> {
    /// In words, why the method kept none of its rounds; None when a round was kept or none ran.
    pub fn refused(&self) -> Option<String> {
        let limit = self.moulds_distance_limit?;
        let first = self.mould_rounds.first()?;
        if self.mould_rounds.iter().any(|r| r.kept()) {
            return None;
        }
        let (moulds, distance) = (first.moulds(), first.distance_to_reference());
        let moulds = format!("{moulds} mould{}", if moulds == 1 { "" } else { "s" });
        Some(if distance > limit {
            format!(
                "not snapped: on {moulds} exactly the panels would be {distance:.2e} of the diagonal from the reference, over the limit {limit:.2e}"
            )
        } else {
            format!("not snapped: on {moulds} exactly the method's guarantees would not hold")
        })
    }
}

/// The rounds' tolerances, as multiples of δ, in order: δ itself (the snap), then coarser.
pub const SNAP_COARSENING: [f64; 7] = [1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0];

/// What one round of [`fewer_moulds`] found: its coarsening γ, the moulds at δ of the moved
/// panels, and whether it was kept.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoundCount {
    pub coarsening: f64,
    pub moulds: usize,
    pub kept: bool,
}

/// How a method's rounds toward fewer moulds go.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoundSchedule {
    /// The rounds' tolerances, as multiples of δ, in order.
    pub coarsening: &'static [f64],
    /// The method's pull gives every panel its mould's curvature exactly (ST with support
    /// structure, SQ): each round starts from the last kept result and skips a tolerance that
    /// would not lower its count; the first round whose guarantees hold is kept (it is the
    /// snap), later ones with fewer moulds. Otherwise the pull draws the panels toward their
    /// moulds (the angle-minimizing ST method): each round starts from the last round's result
    /// with δ measured on its panels, a round is kept with fewer moulds than before the rounds,
    /// and [`MouldHook::snap`] gives the panels their moulds' radii after the rounds.
    pub exact: bool,
}

/// The schedule of the methods that give every panel a prescribed curvature exactly.
pub const EXACT_ROUNDS: RoundSchedule = RoundSchedule { coarsening: &SNAP_COARSENING, exact: true };

/// A method's part in the rounds toward fewer moulds ([`fewer_moulds`], the one engine): how
/// its result is pulled to the moulds' curvatures, and what a round reports.
pub trait MouldHook {
    type Result: Clone;
    /// A round's figures, as the method's report lists them.
    type Round;
    type Error: From<Cancelled>;

    fn schedule(&self) -> RoundSchedule;
    fn panels<'r>(&self, result: &'r Self::Result) -> &'r [Panel];
    /// Moves `from` so that every panel has (or draws toward) the signed curvature given, per
    /// panel in order: the moved result and whether the method's guarantees hold on it; None
    /// where it cannot (the rounds end).
    fn pull(&mut self, from: &Self::Result, curvatures: &[f64]) -> Result<Option<(Self::Result, bool)>, Self::Error>;
    /// A round's figures.
    fn round(&self, moved: &Self::Result, count: RoundCount) -> Self::Round;
    /// After the rounds of a schedule that is not exact: `kept` (the last kept result, else the
    /// start) with every panel at its mould's radius where the method can, and the moulds; the
    /// snapped result is None where it misses the method's guarantees.
    fn snap(&mut self, _kept: &Self::Result, _fabrication: &Fabrication) -> Option<(Option<Self::Result>, MouldSnap)> {
        None
    }
    /// The largest distance to the reference a round may reach (relative to the diagonal).
    fn distance_limit(&self) -> f64;
    fn progress(&mut self, p: Progress) -> Result<(), Cancelled>;
}

/// Per-panel curvatures (a round's, in panel order) as per-face ones of a mesh of `faces` faces,
/// NaN where a face has no panel, each multiplied by `scale` (a frame's).
pub fn per_face(panels: &[Panel], per_panel: &[f64], faces: usize, scale: f64) -> Vec<f64> {
    let mut curvatures = vec![f64::NAN; faces];
    for (p, &k) in panels.iter().zip(per_panel) {
        curvatures[p.face] = k * scale;
    }
    curvatures
}

/// What the rounds made: the last kept result (None: none was kept) and what they did.
pub struct MouldRun<R, Round> {
    pub best: Option<R>,
    pub outcome: MouldOutcome<Round>,
}

/// The rounds toward fewer moulds (`optimize_moulds`) of every method, from its result `start` on
/// a reference of diagonal `diag`: each round assigns the panels of its start to the moulds of
/// γ δ (the hook's [`RoundSchedule`]) and the hook pulls them to those moulds' curvatures
/// (signed, per panel); a round is kept when the method's guarantees hold and the moulds at δ
/// fell, and the rounds end at the first that breaks them. A kept round's panels of an exact
/// schedule have their moulds' radii (measured: [`MouldFits::has_mould_radius`]), so the last is
/// the snap; otherwise the hook snaps after the rounds.
pub fn fewer_moulds<H: MouldHook>(
    hook: &mut H,
    start: &H::Result,
    diag: f64,
    fabrication: &Fabrication,
) -> Result<MouldRun<H::Result, H::Round>, H::Error> {
    let schedule = hook.schedule();
    let fits_before = MouldFits::of(hook.panels(start));
    let delta_before = fabrication.tolerance(&fits_before, diag);
    let before = fabrication.assign(&fits_before, diag).moulds.len();
    let (mut best, mut last) = (None::<H::Result>, None::<H::Result>);
    let mut best_count = if schedule.exact { usize::MAX } else { before };
    let mut snap = Err(SnapLimit::MethodTargets);
    let mut rounds = Vec::new();
    let n = schedule.coarsening.len();
    for (k, &gamma) in schedule.coarsening.iter().enumerate() {
        hook.progress(Progress::new("fewer_moulds", k, n))?;
        let current = if schedule.exact { best.as_ref() } else { last.as_ref() }.unwrap_or(start);
        let fits = MouldFits::of(hook.panels(current));
        let delta = if schedule.exact { delta_before } else { fabrication.tolerance(&fits, diag) };
        let coarse = fits.assign(gamma * delta);
        if schedule.exact && coarse.moulds.len() >= best_count {
            continue;
        }
        let curvatures: Vec<f64> = (0..fits.len())
            .map(|i| {
                let m = coarse.moulds[coarse.panel_mould[i] as usize].curvature;
                if fits.curvature[i] < 0.0 {
                    -m
                } else {
                    m
                }
            })
            .collect();
        let Some((moved, holds)) = hook.pull(current, &curvatures)? else {
            break;
        };
        let moved_fits = MouldFits::of(hook.panels(&moved));
        let count = fabrication.assign(&moved_fits, diag).moulds.len();
        let kept = holds && count < best_count;
        rounds.push(hook.round(&moved, RoundCount { coarsening: gamma, moulds: count, kept }));
        if !holds {
            break;
        }
        if kept {
            best_count = count;
            if schedule.exact {
                let limits = coarse
                    .panel_mould
                    .iter()
                    .enumerate()
                    .map(|(i, &j)| (!moved_fits.has_mould_radius(i, coarse.moulds[j as usize].curvature, diag)).then_some(SnapLimit::Missed))
                    .collect();
                // Snapped panels are cut from their moulds with no deviation: the fit is at δ.
                snap = Ok(MouldSnap { moulds: MouldAssignment { tolerance: delta, ..coarse }, limits });
            }
        }
        match (schedule.exact, kept) {
            (true, true) => best = Some(moved),
            (true, false) => {}
            (false, true) => {
                best = Some(moved.clone());
                last = Some(moved);
            }
            (false, false) => last = Some(moved),
        }
    }
    hook.progress(Progress::new("fewer_moulds", n, n))?;
    if !schedule.exact {
        if let Some((snapped, s)) = hook.snap(best.as_ref().unwrap_or(start), fabrication) {
            snap = Ok(s);
            if snapped.is_some() {
                best = snapped;
            }
        }
    }
    let outcome = MouldOutcome { snap, rounds, before, fits_before, distance_limit: hook.distance_limit() };
    Ok(MouldRun { best, outcome })
}

/// How many moulds: the fewest within a tolerance, or a count (the smallest tolerance that
/// needs no more).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MouldTarget {
    Tolerance(Length),
    Count(usize),
}

/// The default fit tolerance δ: 2 mm.
pub const DEFAULT_MOULD_TOLERANCE: Length = Length { value: 2.0, unit: Some(Units::Mm) };

/// The fabrication settings of a design: its model unit and the moulds asked for.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Fabrication {
    pub units: Units,
    pub moulds: MouldTarget,
}

impl Default for Fabrication {
    fn default() -> Self {
        Self { units: Units::M, moulds: MouldTarget::Tolerance(DEFAULT_MOULD_TOLERANCE) }
    }
}

/// The number of moulds K a design may ask for.
pub const MOULD_COUNT_RANGE: ParamRange<usize> = ParamRange::new("moulds", 1, 10_000);

impl LinkFields for Fabrication {
    /// Units and moulds only when not the defaults, so older links stay as they were.
    fn write_link(&self, link: &mut LinkWriter) {
        if self.units != Units::default() {
            link.text("units", &self.units.to_string());
        }
        match self.moulds {
            MouldTarget::Tolerance(t) if t == DEFAULT_MOULD_TOLERANCE => {}
            MouldTarget::Tolerance(t) => link.text("mould_tol", &percent_encode(&t.to_string())),
            MouldTarget::Count(k) => link.count("moulds", k),
        }
    }

    fn read_link(&mut self, link: &mut LinkReader) {
        if let Some(u) = link.parsed("units", |v| v.parse::<Units>().ok()) {
            self.units = u;
        }
        if let Some(t) = link.parsed("mould_tol", |v| v.parse::<Length>().ok()) {
            self.moulds = MouldTarget::Tolerance(t);
        }
        if let Some(k) = link.count("moulds", MOULD_COUNT_RANGE) {
            self.moulds = MouldTarget::Count(k);
        }
    }
}

impl Fabrication {
    /// The moulds of `fits` as asked, in model units; `diagonal` (of the result) bounds the
    /// tolerance a count can need.
    pub fn assign(&self, fits: &MouldFits, diagonal: f64) -> MouldAssignment {
        fits.assign(self.tolerance(fits, diagonal))
    }

    /// The fit tolerance asked for, in model units (for a count, the smallest that allows it).
    pub fn tolerance(&self, fits: &MouldFits, diagonal: f64) -> f64 {
        match self.moulds {
            MouldTarget::Tolerance(length) => length.in_model_units(self.units),
            MouldTarget::Count(k) => fits.tolerance_for_count(k, diagonal),
        }
    }
}

/// Distinct mould colours; mould j has colour j mod this.
pub const MOULD_COLOURS: usize = 16;

/// The display colour of mould `j` (RGB in [0, 1]): hues a golden angle apart, so neighbouring
/// ids differ, repeating every [`MOULD_COLOURS`]; the app and the GLB's materials use the same.
/// Mould 0 is a calm blue, and no mould is red (30° to 330° only): red says a result failed.
pub fn mould_colour(j: usize) -> [f32; 3] {
    let hue = 0.5 + (0.57 + (j % MOULD_COLOURS) as f32 * 0.618_034).fract() * 5.0;
    let (s, v) = (0.55, 0.9);
    let f = hue.fract();
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    match hue as u32 {
        0 => [v, t, p],
        1 => [q, v, p],
        2 => [p, v, t],
        3 => [p, q, v],
        4 => [t, p, v],
        _ => [v, p, q],
    }
}

/// Distance from x (h = ⟨x − c, n⟩, q = |x − c|²) to the sphere of signed curvature `k` tangent
/// at c with normal n (centre c + n/k; the tangent plane for k = 0), without cancellation.
pub fn tangent_sphere_distance(k: f64, h: f64, q: f64) -> f64 {
    (k * q - 2.0 * h).abs() / (1.0 + (k * k * q - 2.0 * k * h + 1.0).max(0.0).sqrt())
}

/// The fewest values such that every interval `[lo, hi]` holds one, ascending: sorted by right
/// end, each interval not yet holding a value adds its right end. Optimal (an exchange argument:
/// any solution needs a value in the first interval not yet hit, and its right end hits the most
/// of the rest).
pub fn fewest_stabbing_values(intervals: &[[f64; 2]]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..intervals.len()).collect();
    order.sort_unstable_by(|&a, &b| intervals[a][1].total_cmp(&intervals[b][1]));
    let mut values: Vec<f64> = Vec::new();
    for i in order {
        let [lo, hi] = intervals[i];
        if values.last().is_none_or(|&v| v < lo) {
            values.push(hi);
        }
    }
    values
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// Brute force: the smallest k such that some k of the candidate values (the right ends)
    /// hit every interval.
    fn brute_force(intervals: &[[f64; 2]]) -> usize {
        let ends: Vec<f64> = intervals.iter().map(|i| i[1]).collect();
        let n = ends.len();
        (0..=n)
            .find(|&k| {
                (0u32..1 << n)
                    .filter(|m| m.count_ones() as usize == k)
                    .any(|m| intervals.iter().all(|&[lo, hi]| (0..n).any(|j| m & (1 << j) != 0 && ends[j] >= lo && ends[j] <= hi)))
            })
            .unwrap()
    }

    #[test]
    fn no_mould_colour_reads_as_an_error() {
        for j in 0..MOULD_COLOURS {
            let [r, g, b] = mould_colour(j);
            // Red dominates neither green nor blue by much: a mould never looks like a failure.
            assert!(r < 1.4 * g.max(b), "mould {j}: {:?}", [r, g, b]);
        }
        let [r, _, b] = mould_colour(0);
        assert!(b > r, "mould 0 is blue");
        let distinct: std::collections::HashSet<_> = (0..MOULD_COLOURS).map(|j| mould_colour(j).map(|c| (c * 255.0) as u8)).collect();
        assert_eq!(distinct.len(), MOULD_COLOURS);
    }

    #[test]
    fn the_sweep_is_optimal_against_brute_force() {
        let mut rng = Rng(7);
        for case in 0..400 {
            let n = 1 + case % 11;
            let intervals: Vec<[f64; 2]> = (0..n)
                .map(|_| {
                    let a = rng.range(0.0, 10.0);
                    [a, a + rng.range(0.0, 3.0)]
                })
                .collect();
            let values = fewest_stabbing_values(&intervals);
            assert!(intervals.iter().all(|&[lo, hi]| values.iter().any(|&v| v >= lo && v <= hi)), "case {case}: an interval is missed");
            assert_eq!(values.len(), brute_force(&intervals), "case {case}: {intervals:?}");
        }
    }

    #[test]
    fn interval_ends_are_at_the_tolerance() {
        let mut rng = Rng(3);
        for _ in 0..1000 {
            let (h, q, d) = (rng.range(-0.3, 0.3), rng.range(0.5, 2.0), rng.range(1e-4, 0.05));
            let q = q.max(h * h);
            for k in [2.0 * (h - d) / (q - d * d), 2.0 * (h + d) / (q - d * d)] {
                assert!((tangent_sphere_distance(k, h, q) - d).abs() < 1e-12, "h {h} q {q} δ {d} κ {k}");
            }
            let inside = 2.0 * h / q;
            assert!(tangent_sphere_distance(inside, h, q) < 1e-12);
        }
    }
}
