//! [`Race`]: copies of one planner on several threads, each with its own random stream; the
//! path found in the fewest iterations wins.
//!
//! A sampling planner's time to a path on a hard problem (a goal wedged between shelf boards)
//! is spread roughly exponentially: most runs are quick and a few are very slow. Copies with
//! independent streams fail together only as often as each fails alone, squared, so a second
//! core turns a 5 % chance of missing a deadline into about 0.25 %.
//!
//! The result is reproducible: it does not depend on which thread happens to finish first.
//! A copy that finds a path after `n` iterations tells the others, and each of them stops once
//! it has made `n` iterations of its own; of the paths found, the one found in the fewest
//! iterations wins (the lowest thread index on a tie). With an iteration budget, the same seed
//! gives the same path on any machine; with a time budget, as for a single planner, only
//! whether a path is found within the time depends on the machine's speed.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use rand::{Rng, RngExt, SeedableRng};

use crate::error::PlanError;
use crate::motion::MotionValidator;
use crate::planner::{Budget, PlanRequest, Planner, Solution, with_stop_at};
use crate::space::Space;
use crate::validity::StateValidator;

/// Runs `threads` copies of `planner` at once (see the [module](self) documentation).
///
/// Thread 0 plans on the calling thread with the caller's validators; the others plan on
/// clones of them. Each copy draws its random stream from a seed taken from the caller's
/// generator; a race of one thread plans exactly as the planner alone does, with the caller's
/// generator itself. Every plan clones the planner and both validators for each thread
/// after the first: a [`LazyPrm`](crate::LazyPrm) with a large roadmap pays for copying it.
///
/// ```
/// use hearth_planning::motion::MotionValidator;
/// use hearth_planning::planner::{Budget, Goal, PlanRequest};
/// use hearth_planning::race::Race;
/// use hearth_planning::space::JointSpace;
/// use hearth_planning::validity::StateValidator;
/// use hearth_planning::BiRrt;
/// use rand::SeedableRng;
///
/// // A wall at x = 0.5 with a gap above y = 0.8.
/// #[derive(Clone)]
/// struct Wall(u64);
/// impl StateValidator for Wall {
///     fn is_valid(&mut self, q: &[f64]) -> bool { self.0 += 1; (q[0] - 0.5).abs() > 0.05 || q[1] > 0.8 }
///     fn checks(&self) -> u64 { self.0 }
/// }
/// let space = JointSpace::new(&[0.0, 0.0], &[1.0, 1.0], &[false, false])?;
/// let request = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.1]));
/// let mut race = Race::new(BiRrt::default(), 2);
/// let mut plan = |seed: u64| {
///     let mut motion = MotionValidator::new(space.clone(), 0.01);
///     let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
///     race.plan(&mut motion, &mut Wall(0), &request, &Budget::iterations(10_000), &mut rng).unwrap()
/// };
/// let (a, b) = (plan(7), plan(7));
/// assert_eq!(a.path, b.path); // the same seed, the same path, whichever thread won
/// assert!(a.path.states.iter().any(|q| q[1] > 0.8));
/// # Ok::<(), hearth_planning::space::SpaceError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Race<P> {
    /// The planner that every thread runs a copy of. After a race it holds the winning
    /// copy (whose state, such as [`LazyPrm`](crate::LazyPrm)'s roadmap, is the winner's).
    pub planner: P,
    /// Copies planning at once (0 reads as 1).
    pub threads: usize,
}

impl<P> Race<P> {
    /// A race of `threads` copies of `planner`.
    ///
    /// ```
    /// let race = hearth_planning::race::Race::new(hearth_planning::Rrt::default(), 4);
    /// assert_eq!(race.threads, 4);
    /// ```
    pub fn new(planner: P, threads: usize) -> Self {
        Self { planner, threads }
    }

    /// Plans as [`Planner::plan`] does, with every copy under the same `budget`. Returns the
    /// path found in the fewest iterations (its statistics are the winning copy's); when no
    /// copy finds one, thread 0's error (every copy checks the request the same way, so bad
    /// input and invalid starts and goals are reported as the planner alone reports them).
    ///
    /// ```
    /// use hearth_planning::motion::MotionValidator;
    /// use hearth_planning::planner::{Budget, Goal, PlanRequest};
    /// use hearth_planning::race::Race;
    /// use hearth_planning::space::JointSpace;
    /// use hearth_planning::validity::StateValidator;
    /// use hearth_planning::{BiRrt, PlanError};
    /// use rand::SeedableRng;
    ///
    /// // A wall at x = 0.5, closed.
    /// #[derive(Clone)]
    /// struct Wall;
    /// impl StateValidator for Wall {
    ///     fn is_valid(&mut self, q: &[f64]) -> bool { (q[0] - 0.5).abs() > 0.05 }
    ///     fn checks(&self) -> u64 { 0 }
    /// }
    /// let space = JointSpace::new(&[0.0, 0.0], &[1.0, 1.0], &[false, false])?;
    /// let mut motion = MotionValidator::new(space, 0.01);
    /// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    /// let mut race = Race::new(BiRrt::default(), 2);
    /// // A start inside the wall: reported as BiRRT alone reports it.
    /// let inside = PlanRequest::new(vec![0.5, 0.1], Goal::Config(vec![0.9, 0.1]));
    /// let err = race.plan(&mut motion, &mut Wall, &inside, &Budget::iterations(100), &mut rng);
    /// assert!(matches!(err, Err(PlanError::InvalidStart { .. })));
    /// // No way through: every copy stops at the budget, and thread 0's timeout is returned.
    /// let across = PlanRequest::new(vec![0.1, 0.1], Goal::Config(vec![0.9, 0.1]));
    /// let err = race.plan(&mut motion, &mut Wall, &across, &Budget::iterations(200), &mut rng);
    /// assert!(matches!(err, Err(PlanError::Timeout { .. })));
    /// # Ok::<(), hearth_planning::space::SpaceError>(())
    /// ```
    ///
    /// # Errors
    /// As [`Planner::plan`].
    pub fn plan<S, V, R>(
        &mut self,
        motion: &mut MotionValidator<S>,
        validator: &mut V,
        request: &PlanRequest,
        budget: &Budget,
        rng: &mut R,
    ) -> Result<Solution, PlanError>
    where
        P: Planner<S> + Clone + Send,
        S: Space + Clone + Send,
        V: StateValidator + Clone + Send,
        R: Rng + ?Sized,
    {
        let threads = self.threads.max(1);
        if threads == 1 {
            return self.planner.plan(motion, validator, request, budget, rng);
        }
        let seeds: Vec<u64> = (0..threads).map(|_| rng.random()).collect();
        let stop = Arc::new(AtomicU64::new(u64::MAX));
        // One copy's run: its result, reported to the others when it found a path.
        let run = |planner: &mut P, motion: &mut MotionValidator<S>, validator: &mut V, seed: u64| {
            let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
            let out = with_stop_at(&stop, || planner.plan(motion, validator, request, budget, &mut rng));
            if let Ok(solution) = &out {
                stop.fetch_min(solution.stats.iterations, Ordering::Relaxed);
            }
            out
        };
        let (first, others) = std::thread::scope(|scope| {
            let handles: Vec<_> = seeds[1..]
                .iter()
                .map(|&seed| {
                    let (mut planner, mut motion, mut validator) =
                        (self.planner.clone(), motion.clone(), validator.clone());
                    let run = &run;
                    scope.spawn(move || {
                        let out = run(&mut planner, &mut motion, &mut validator, seed);
                        (out, planner)
                    })
                })
                .collect();
            let first = run(&mut self.planner, motion, validator, seeds[0]);
            let others: Vec<_> = handles
                .into_iter()
                .map(|h| h.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)))
                .collect();
            (first, others)
        });
        // The path found in the fewest iterations; thread 0 first among equals.
        let mut best: Option<(u64, usize)> = first.as_ref().ok().map(|s| (s.stats.iterations, 0));
        for (i, (out, _)) in others.iter().enumerate() {
            if let Ok(s) = out
                && best.is_none_or(|(n, _)| s.stats.iterations < n)
            {
                best = Some((s.stats.iterations, i + 1));
            }
        }
        match best {
            Some((_, 0)) | None => first,
            Some((_, i)) => {
                let (out, planner) = others.into_iter().nth(i - 1).expect("a thread's result");
                self.planner = planner;
                out
            }
        }
    }
}
