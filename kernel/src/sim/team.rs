//! The threads of a run, kept awake between the parallel phases of its steps.
//!
//! A step has two parallel phases (pairs, then particles) of a few hundred microseconds
//! each at 20,000 particles. Rayon's idle worker sleeps in the kernel after a few dozen
//! rounds without work, and its waiting thread sleeps at the end of a join; on a virtual
//! machine each wake-up is a futex call and an interrupt to a halted CPU. `strace` of a
//! two-thread run found 3,293 futex calls and 100,377 `sched_yield`s in 5,000 steps.
//! OpenMP runtimes avoid that with an active wait:
//! the team's threads spin between regions. [`Team`] is that, for the run loop only: the
//! leader (the thread that runs the steps) posts each phase's work, each helper that comes
//! in time takes items of it (see [`Team::map`]), and between phases the helpers poll for
//! the next phase and for rayon work (the neighbour rebuild stays on rayon), yielding the
//! CPU to the operating system when they have polled long without finding any.
//!
//! Which thread computes an item never changes a bit: items own disjoint data, and their
//! results come back in item order.

use crate::neighbor::chunks_per_task;
use rayon::prelude::*;
use std::cell::UnsafeCell;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// Idle polls a waiting thread spins (a CPU hint between polls) before each later poll
/// also yields to the operating system. A poll takes about 50 ns on the project's VM (a
/// rayon `yield_now` and a CPU hint, measured alone), so this is about 100 microseconds:
/// longer than any wait between two phases of a step, so within a run a thread gives up
/// its CPU only where the leader works alone for longer.
const SPINS_BEFORE_YIELD: u32 = 2_000;

/// The work every thread of the team runs once per phase, its lifetime erased.
type Job = *const (dyn Fn(usize) + Sync + 'static);

/// [`Team::gate`]: set once the leader's own part of the job is done; no helper may
/// enter the job after it.
const CLOSED: u64 = 1 << 31;
/// [`Team::gate`]: the helpers inside the job.
const INSIDE: u64 = CLOSED - 1;

/// A leader and its helpers (see the module's documentation).
pub(crate) struct Team {
    helpers: usize,
    /// The current job's number (high 32 bits), whether it is [`CLOSED`], and how many
    /// helpers are [`INSIDE`] it. A helper takes part in a job only if it enters before the
    /// leader closes it, and the leader waits only for those inside: a helper the operating
    /// system has not scheduled (more threads than cores) does not hold up a phase, since
    /// the leader takes the items of its run.
    gate: AtomicU64,
    /// Written by the leader before it opens a job; read by helpers inside it.
    job: UnsafeCell<Option<Job>>,
    /// The first panic of a helper's part of the current job.
    panic: Mutex<Option<Box<dyn std::any::Any + Send>>>,
    quit: AtomicBool,
}

// SAFETY: `job` is written only by the leader while no helper is inside a job (the previous
// job closed with none inside), and read by a helper only inside one (its entry, Acquire,
// pairs with the leader's opening store, Release).
unsafe impl Sync for Team {}

impl Team {
    /// A team of the calling thread (the leader) and `helpers` threads that will call
    /// [`Team::help`].
    pub fn new(helpers: usize) -> Team {
        Team {
            helpers,
            gate: AtomicU64::new(0),
            job: UnsafeCell::new(None),
            panic: Mutex::new(None),
            quit: AtomicBool::new(false),
        }
    }

    /// Runs `f(thread)` on the leader (thread 0) and on each helper (1 to `helpers`) that
    /// comes before the leader's own call returns, and returns when all of those are done,
    /// so that `f` may borrow the leader's data. `f` must therefore do all the work when
    /// the leader alone runs it. A panic of any part is raised here, after all are done.
    /// Leader only.
    fn run_on_all(&self, f: &(dyn Fn(usize) + Sync)) {
        if self.helpers == 0 {
            f(0);
            return;
        }
        let job: *const (dyn Fn(usize) + Sync + '_) = f;
        // SAFETY: only the lifetime changes. Helpers call the job only inside it, and this
        // function returns only when none is inside and none can enter.
        let job: Job = unsafe { std::mem::transmute(job) };
        // SAFETY: no helper is inside a job, so none reads `job` now.
        unsafe { *self.job.get() = Some(job) };
        let number = (self.gate.load(Ordering::Relaxed) >> 32).wrapping_add(1) & 0xffff_ffff;
        self.gate.store(number << 32, Ordering::Release);
        let mine = catch_unwind(AssertUnwindSafe(|| f(0)));
        let mut gate = self.gate.fetch_or(CLOSED, Ordering::AcqRel);
        let mut idle = 0;
        while gate & INSIDE != 0 {
            wait(&mut idle);
            gate = self.gate.load(Ordering::Acquire);
        }
        if let Err(p) = mine {
            resume_unwind(p);
        }
        if let Some(p) = self.panic.lock().unwrap_or_else(|e| e.into_inner()).take() {
            resume_unwind(p);
        }
    }

    /// Helper `thread`'s (1 to `helpers`) part of a run: each job the leader posts, and
    /// rayon's work between them, until [`Team::release`].
    pub fn help(&self, thread: usize) {
        // Job numbers start at 1, so a helper that starts late still tries the current one.
        // (A job it misses, even at the numbers' wrap after 2^32 jobs, costs only its help:
        // the leader does whatever no helper takes.)
        let mut seen = 0;
        let mut idle = 0;
        loop {
            let gate = self.gate.load(Ordering::Acquire);
            if gate >> 32 != seen {
                seen = gate >> 32;
                if self.enter(gate) {
                    // SAFETY: see `impl Sync`; the leader keeps the job alive while this
                    // helper is inside.
                    let job = unsafe { (*self.job.get()).expect("an open job") };
                    let done = catch_unwind(AssertUnwindSafe(|| unsafe { (*job)(thread) }));
                    if let Err(p) = done {
                        let mut first = self.panic.lock().unwrap_or_else(|e| e.into_inner());
                        first.get_or_insert(p);
                    }
                    self.gate.fetch_sub(1, Ordering::Release);
                }
                idle = 0;
            } else if self.quit.load(Ordering::Acquire) {
                return;
            } else if rayon::yield_now() == Some(rayon::Yield::Executed) {
                idle = 0;
            } else {
                wait(&mut idle);
            }
        }
    }

    /// Enters the job `gate` (as loaded) names, unless the leader closed it first.
    fn enter(&self, mut gate: u64) -> bool {
        let number = gate >> 32;
        while gate >> 32 == number && gate & CLOSED == 0 {
            match self.gate.compare_exchange_weak(
                gate,
                gate + 1,
                Ordering::AcqRel,
                Ordering::Acquire,
            ) {
                Ok(_) => return true,
                Err(now) => gate = now,
            }
        }
        false
    }

    /// Lets the helpers return from [`Team::help`]. Leader only, after its last job.
    pub fn release(&self) {
        self.quit.store(true, Ordering::Release);
    }

    /// `f(k, items[k])` for every item, spread over the team; the results in item order.
    ///
    /// Each thread starts on its own equal run of consecutive items, in order, and one
    /// that finishes its run takes items from the far end of another's. So threads write
    /// next to each other's items at run ends only: handing out items one by one from a
    /// shared counter interleaved the threads item by item, and the cache lines at each
    /// item's edges went back and forth (the particle phase took 50 % longer on two threads).
    pub fn map<T: Send, R: Send>(&self, items: Vec<T>, f: impl Fn(usize, T) -> R + Sync) -> Vec<R> {
        if self.helpers == 0 {
            return items
                .into_iter()
                .enumerate()
                .map(|(k, t)| f(k, t))
                .collect();
        }
        let n = items.len();
        let slots = Slots(
            items
                .into_iter()
                .map(|t| UnsafeCell::new((Some(t), None)))
                .collect(),
        );
        let threads = self.helpers + 1;
        let runs: Vec<Run> = (0..threads)
            .map(|t| Run::new(t * n / threads, (t + 1) * n / threads))
            .collect();
        self.run_on_all(&|me| {
            let others = (1..threads).map(|d| &runs[(me + d) % threads]);
            while let Some(k) = runs[me]
                .take_front()
                .or_else(|| others.clone().find_map(Run::take_back))
            {
                // SAFETY: the runs hand out each index once, so this thread alone
                // touches slot k.
                let slot = unsafe { slots.take(k) };
                let item = slot.0.take().expect("each item once");
                slot.1 = Some(f(k, item));
            }
        });
        slots
            .0
            .into_iter()
            .map(|s| s.into_inner().1.expect("every item done"))
            .collect()
    }
}

/// The items `front..back` of a thread's run not yet taken, packed in one word so that the
/// owner taking from the front and a thief from the back never take the same item.
struct Run(AtomicU64);

impl Run {
    fn new(front: usize, back: usize) -> Run {
        Run(AtomicU64::new(((front as u64) << 32) | back as u64))
    }

    fn take_front(&self) -> Option<usize> {
        self.take(|front, back| (front < back).then(|| (front, (front + 1, back))))
    }

    fn take_back(&self) -> Option<usize> {
        self.take(|front, back| (front < back).then(|| (back - 1, (front, back - 1))))
    }

    /// Takes the item `pick` chooses from (front, back), leaving the range it returns.
    fn take(
        &self,
        pick: impl Fn(usize, usize) -> Option<(usize, (usize, usize))>,
    ) -> Option<usize> {
        let mut now = self.0.load(Ordering::Acquire);
        loop {
            let (front, back) = ((now >> 32) as usize, (now & 0xffff_ffff) as usize);
            let (item, (f, b)) = pick(front, back)?;
            let next = ((f as u64) << 32) | b as u64;
            match self
                .0
                .compare_exchange_weak(now, next, Ordering::AcqRel, Ordering::Acquire)
            {
                Ok(_) => return Some(item),
                Err(seen) => now = seen,
            }
        }
    }
}

/// `f(k, items[k])` for every item, the results in item order: on `team` when there is
/// one (within [`super::Simulation::run`]), otherwise as rayon tasks of the current pool,
/// one item per task when several threads share it.
pub(crate) fn map_items<T: Send, R: Send>(
    team: Option<&Team>,
    items: Vec<T>,
    f: impl Fn(usize, T) -> R + Sync,
) -> Vec<R> {
    match team {
        Some(team) => team.map(items, f),
        None => items
            .into_par_iter()
            .enumerate()
            .with_max_len(chunks_per_task())
            .map(|(k, t)| f(k, t))
            .collect(),
    }
}

/// Items and their results, one cell per item.
struct Slots<T, R>(Vec<UnsafeCell<(Option<T>, Option<R>)>>);

// SAFETY: each cell is accessed by one thread at a time (see `Team::map`).
unsafe impl<T: Send, R: Send> Sync for Slots<T, R> {}

impl<T, R> Slots<T, R> {
    /// Item k's cell.
    ///
    /// # Safety
    /// No other thread may access cell k while the reference lives.
    #[allow(clippy::mut_from_ref)]
    unsafe fn take(&self, k: usize) -> &mut (Option<T>, Option<R>) {
        unsafe { &mut *self.0[k].get() }
    }
}

/// One idle poll's pause: a CPU hint, and after [`SPINS_BEFORE_YIELD`] polls also a yield
/// to the operating system, so that a thread waiting on a busy machine lets others run.
fn wait(idle: &mut u32) {
    *idle = idle.saturating_add(1);
    if *idle < SPINS_BEFORE_YIELD {
        std::hint::spin_loop();
    } else {
        std::thread::yield_now();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_team<R: Send>(helpers: usize, lead: impl FnOnce(&Team) -> R + Send) -> R {
        let team = Team::new(helpers);
        std::thread::scope(|s| {
            for h in 1..=helpers {
                let team = &team;
                s.spawn(move || team.help(h));
            }
            let out = catch_unwind(AssertUnwindSafe(|| lead(&team)));
            team.release();
            out.unwrap_or_else(|p| resume_unwind(p))
        })
    }

    #[test]
    fn map_returns_every_result_in_item_order() {
        for helpers in 0..3 {
            let out = with_team(helpers, |team| {
                (0..50)
                    .map(|round| team.map((0..round).collect(), |k, x: usize| (k, x * x)))
                    .collect::<Vec<_>>()
            });
            for (round, r) in out.iter().enumerate() {
                let expected: Vec<(usize, usize)> = (0..round).map(|x| (x, x * x)).collect();
                assert_eq!(r, &expected, "{helpers} helpers, round {round}");
            }
        }
    }

    #[test]
    fn a_helper_that_never_comes_does_not_hold_up_the_leader() {
        // A team of two whose helper thread never runs (as when the operating system
        // schedules more threads than it has cores): the leader does every item.
        let team = Team::new(1);
        for round in 0..20 {
            let out = team.map((0..round).collect(), |k, x: usize| k + x);
            assert_eq!(out, (0..round).map(|x| 2 * x).collect::<Vec<_>>());
        }
    }

    #[test]
    fn helpers_take_part() {
        let threads = with_team(1, |team| {
            let ids = team.map((0..64).collect(), |_, _: i32| {
                std::thread::sleep(std::time::Duration::from_millis(1));
                std::thread::current().id()
            });
            let mut ids: Vec<_> = ids.into_iter().collect();
            ids.sort_by_key(|id| format!("{id:?}"));
            ids.dedup();
            ids.len()
        });
        assert_eq!(threads, 2);
    }

    #[test]
    fn a_helpers_panic_reaches_the_leader_after_the_job() {
        let r = catch_unwind(AssertUnwindSafe(|| {
            with_team(1, |team| {
                team.map((0..64).collect(), |k, _: i32| {
                    std::thread::sleep(std::time::Duration::from_micros(200));
                    assert!(k != 40, "item 40 fails");
                })
            })
        }));
        let msg = r.expect_err("the panic is raised");
        let msg = msg
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| msg.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        assert!(msg.contains("item 40 fails"), "{msg}");
    }
}
