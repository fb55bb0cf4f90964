//! Splitting per-strand work over std threads (the core only takes ranges).

use crate::status::Failure;
use crate::PelageStatus;
use pelage_core::Error;
use std::ops::Range;

/// Most threads `thread_count` may ask for beyond the machine's cores.
const MAX_THREADS: usize = 64;

/// Threads to use for a `thread_count` parameter: 0 means all cores; a
/// host may ask for more threads than cores (up to 64, or the core count
/// when larger), and the cap keeps a huge value from spawning one thread
/// per strand.
pub(crate) fn thread_total(thread_count: u32) -> usize {
    // asked once: on Linux the answer reads cgroup files (tens of
    // microseconds), which a renderer's per-patch calls would pay each time
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    if thread_count == 1 {
        return 1;
    }
    let cores = *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    match thread_count {
        0 => cores,
        n => (n as usize).min(cores.max(MAX_THREADS)),
    }
}

/// Runs `work` on contiguous ranges of `0..n`, each with its own part of
/// `out` (`per` elements per strand; the last part takes the rest), on
/// scoped threads, and returns the results in range order. One range runs on
/// the calling thread, so a single thread spawns nothing.
pub(crate) fn split_over_threads<T: Send, R: Send>(
    n: usize,
    thread_count: u32,
    out: &mut [T],
    per: usize,
    work: impl Fn(Range<usize>, &mut [T]) -> R + Sync,
) -> Result<Vec<R>, Failure> {
    let threads = thread_total(thread_count).clamp(1, n.max(1));
    if threads == 1 {
        return Ok(vec![work(0..n, out)]);
    }
    run_parts(even_parts(n, threads, out, per), |(range, mine)| {
        work(range, mine)
    })
}

/// `0..n` cut into `k` contiguous ranges as even as they come, each with
/// its part of `out` (`per` elements per item; the last part takes the
/// rest).
fn even_parts<T>(n: usize, k: usize, out: &mut [T], per: usize) -> Vec<(Range<usize>, &mut [T])> {
    let mut rest = out;
    let mut parts = Vec::with_capacity(k);
    for t in 0..k {
        let range = t * n / k..(t + 1) * n / k;
        let take = if t + 1 == k {
            rest.len()
        } else {
            range.len() * per
        };
        let (mine, tail) = std::mem::take(&mut rest).split_at_mut(take);
        rest = tail;
        parts.push((range, mine));
    }
    parts
}

/// Runs `check` on the ranges [`split_over_threads`] would use, in parallel,
/// and returns the error of the first failing range (so the message does
/// not depend on timing), with indices into the whole input.
pub(crate) fn check_over_threads(
    n: usize,
    thread_count: u32,
    check: impl Fn(Range<usize>) -> Result<(), Error> + Sync,
) -> Result<(), Failure> {
    let results = split_over_threads(n, thread_count, &mut [0u8; 0], 0, |range, _| {
        let start = range.start;
        check(range).map_err(|e| e.shifted(start))
    })?;
    Ok(results.into_iter().collect::<Result<(), Error>>()?)
}

/// A progress callback: `user_data` as given with it, `fraction` the share of
/// the work done in [0, 1]. Returns true to go on, false to cancel.
pub type PelageProgressFn =
    Option<unsafe extern "C" fn(user_data: *mut std::ffi::c_void, fraction: f64) -> bool>;

/// How a long call runs: the threads it splits its work over and the
/// progress callback that hears from it and may cancel it. A
/// zero-initialised PelageRun (or `pelage_run_defaults()`) uses every core
/// and reports nothing.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PelageRun {
    /// Threads of the call's own to split the work over: 0 = every core,
    /// 1 = the calling thread only; at most max(cores, 64). The results are
    /// bitwise identical for any value.
    pub thread_count: u32,
    /// Optional progress callback (NULL: none), called on the calling
    /// thread with a never-decreasing share of the work done (0 first, 1
    /// last); returning false cancels (PELAGE_STATUS_CANCELLED).
    pub progress: PelageProgressFn,
    /// Passed unchanged to `progress`.
    pub progress_user_data: *mut std::ffi::c_void,
}

/// Every core, no progress callback.
///
/// Thread safety: free.
#[no_mangle]
pub extern "C" fn pelage_run_defaults() -> PelageRun {
    PelageRun {
        thread_count: 0,
        progress: None,
        progress_user_data: std::ptr::null_mut(),
    }
}

impl PelageRun {
    /// This run's progress callback, reporting over the whole call.
    pub(crate) fn progress(&self) -> Progress {
        Progress {
            callback: self.progress,
            user_data: self.progress_user_data,
            from: 0.0,
            span: 1.0,
        }
    }
}

/// A host's progress callback and its user data (see `PelageProgressFn`),
/// reporting a part of a call as its share `from..from + span` of the whole.
#[derive(Clone, Copy)]
pub(crate) struct Progress {
    callback: PelageProgressFn,
    user_data: *mut std::ffi::c_void,
    from: f64,
    span: f64,
}

impl Progress {
    /// No callback: every report succeeds.
    pub(crate) fn none() -> Self {
        pelage_run_defaults().progress()
    }

    /// True when the host gave a callback.
    pub(crate) fn is_set(&self) -> bool {
        self.callback.is_some()
    }

    /// The part `from..to` (shares of this one) of the work: its reports
    /// of 0..1 reach the host as `from..to` of this one's.
    pub(crate) fn within(&self, from: f64, to: f64) -> Progress {
        Progress {
            from: self.from + self.span * from,
            span: self.span * (to - from),
            ..*self
        }
    }

    /// Reports `fraction` done; CANCELLED when the host returns false.
    pub(crate) fn report(&self, fraction: f64) -> Result<(), Failure> {
        let Some(callback) = self.callback else {
            return Ok(());
        };
        let share = self.from + self.span * fraction;
        // SAFETY: the host gave this callback and its user data for this
        // call, and calls it on the calling thread only.
        if unsafe { callback(self.user_data, share) } {
            Ok(())
        } else {
            Err(Failure::from(Error::Cancelled))
        }
    }
}

/// Rounds a long call is cut into when it reports progress: the host hears
/// from it (and may cancel) at least this often.
const PROGRESS_ROUNDS: usize = 32;

/// [`split_over_threads`] in rounds of contiguous ranges, calling
/// `progress` on the calling thread before the first round and after each
/// (a never-decreasing share, 1 at the end); a false return stops before
/// the next round with CANCELLED. Without a callback, one round. `work`
/// gets ranges of the whole `0..n` and the matching part of `out`.
pub(crate) fn split_with_progress<T: Send, R: Send>(
    n: usize,
    thread_count: u32,
    out: &mut [T],
    per: usize,
    progress: Progress,
    work: impl Fn(Range<usize>, &mut [T]) -> R + Sync,
) -> Result<Vec<R>, Failure> {
    let mut results = Vec::new();
    in_rounds(n, out, per, progress, |range, part| {
        let start = range.start;
        results.extend(split_over_threads(
            range.len(),
            thread_count,
            part,
            per,
            |sub, p| work(sub.start + start..sub.end + start, p),
        )?);
        Ok(())
    })?;
    Ok(results)
}

/// [`split_in_chunks`] in rounds, reporting as [`split_with_progress`]
/// does.
pub(crate) fn chunks_with_progress<T: Send>(
    n: usize,
    thread_count: u32,
    out: &mut [T],
    per: usize,
    progress: Progress,
    work: impl Fn(Range<usize>, &mut [T]) + Sync,
) -> Result<(), Failure> {
    in_rounds(n, out, per, progress, |range, part| {
        let start = range.start;
        split_in_chunks(range.len(), thread_count, part, per, |sub, p| {
            work(sub.start + start..sub.end + start, p)
        })
    })
}

/// Runs `round` on [`PROGRESS_ROUNDS`] contiguous ranges of `0..n` (one
/// without a callback), each with its part of `out`, reporting the share
/// done before the first and after each.
fn in_rounds<T>(
    n: usize,
    out: &mut [T],
    per: usize,
    progress: Progress,
    mut round: impl FnMut(Range<usize>, &mut [T]) -> Result<(), Failure>,
) -> Result<(), Failure> {
    if !progress.is_set() {
        return round(0..n, out);
    }
    progress.report(0.0)?;
    let rounds = PROGRESS_ROUNDS.min(n.max(1));
    for (range, part) in even_parts(n, rounds, out, per) {
        let end = range.end;
        round(range, part)?;
        // with nothing to do, the one round finishes all of it
        let done = if n == 0 { 1.0 } else { end as f64 / n as f64 };
        progress.report(done)?;
    }
    Ok(())
}

/// Strands (or guides) per chunk of [`split_in_chunks`].
pub(crate) const CHUNK: usize = 256;

/// Runs `work` on chunks of `0..n` ([`CHUNK`] items, `per` elements of
/// `out` each), the threads taking the next chunk as they free up: for
/// work whose cost varies along the items (guides in a crease, or far from
/// their target), where equal ranges would leave a thread idle. Each chunk
/// is a pure function of its items, so the bits do not depend on who ran it.
/// The last chunk's part of `out` takes whatever `out` holds past the
/// others'.
pub(crate) fn split_in_chunks<T: Send>(
    n: usize,
    thread_count: u32,
    out: &mut [T],
    per: usize,
    work: impl Fn(Range<usize>, &mut [T]) + Sync,
) -> Result<(), Failure> {
    split_pairs_in_chunks(
        n,
        thread_count,
        out,
        per,
        &mut [0u8; 0],
        0,
        |range, part, _| work(range, part),
    )
}

/// [`split_in_chunks`] with two outputs: `a` (`per_a` elements an item)
/// and `b` (`per_b`), cut alike.
pub(crate) fn split_pairs_in_chunks<A: Send, B: Send>(
    n: usize,
    thread_count: u32,
    a: &mut [A],
    per_a: usize,
    b: &mut [B],
    per_b: usize,
    work: impl Fn(Range<usize>, &mut [A], &mut [B]) + Sync,
) -> Result<(), Failure> {
    let threads = thread_total(thread_count).clamp(1, n.div_ceil(CHUNK).max(1));
    if threads == 1 {
        work(0..n, a, b);
        return Ok(());
    }
    let chunks = n.div_ceil(CHUNK);
    let parts: Vec<Chunk<A, B>> = cut_chunks(a, CHUNK * per_a, chunks)
        .zip(cut_chunks(b, CHUNK * per_b, chunks))
        .map(|p| std::sync::Mutex::new(Some(p)))
        .collect();
    let next = std::sync::atomic::AtomicUsize::new(0);
    let run = || loop {
        let c = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let Some(slot) = parts.get(c) else { break };
        // each chunk is taken once, by the thread that drew its number
        if let Some((a, b)) = slot.lock().ok().and_then(|mut p| p.take()) {
            work(c * CHUNK..((c + 1) * CHUNK).min(n), a, b);
        }
    };
    split_over_threads(threads, threads as u32, &mut [0u8; 0], 0, |_, _| run())?;
    Ok(())
}

/// A chunk of [`split_pairs_in_chunks`]'s outputs, until a thread takes it.
type Chunk<'p, A, B> = std::sync::Mutex<Option<(&'p mut [A], &'p mut [B])>>;

/// `s` cut into `chunks` parts of `size` elements (the last takes the
/// rest; all empty when `s` is).
fn cut_chunks<T>(s: &mut [T], size: usize, chunks: usize) -> impl Iterator<Item = &mut [T]> {
    let mut rest = s;
    (0..chunks).map(move |c| {
        let take = if c + 1 == chunks {
            rest.len()
        } else {
            size.min(rest.len())
        };
        let (mine, tail) = std::mem::take(&mut rest).split_at_mut(take);
        rest = tail;
        mine
    })
}

/// Runs `a` on a scoped thread while `b` runs on the calling thread, and
/// returns both results. When the thread cannot start, `b` does not run
/// (PANIC); a panic in `a` is PANIC once `b` is done, one in `b` unwinds
/// once `a` is joined.
pub(crate) fn beside<A: Send, B>(
    a: impl FnOnce() -> A + Send,
    b: impl FnOnce() -> B,
) -> Result<(A, B), Failure> {
    std::thread::scope(|scope| {
        let handle = std::thread::Builder::new()
            .spawn_scoped(scope, a)
            .map_err(|e| {
                Failure::new(
                    PelageStatus::Panic,
                    format!("could not start a worker thread ({e})"),
                )
            })?;
        let b = b();
        let a = handle
            .join()
            .map_err(|_| Failure::new(PelageStatus::Panic, "a worker thread panicked"))?;
        Ok((a, b))
    })
}

/// Runs `work` on each of `parts` on scoped threads (the last on the
/// calling thread) and returns the results in order.
pub(crate) fn run_parts<P: Send, R: Send>(
    parts: Vec<P>,
    work: impl Fn(P) -> R + Sync,
) -> Result<Vec<R>, Failure> {
    std::thread::scope(|scope| {
        let work = &work;
        let mut parts = parts;
        let last = parts.pop();
        let mut handles = Vec::with_capacity(parts.len());
        for part in parts {
            match std::thread::Builder::new().spawn_scoped(scope, move || work(part)) {
                Ok(h) => handles.push(h),
                // the scope still joins the threads already running
                Err(e) => {
                    return Err(Failure::new(
                        PelageStatus::Panic,
                        format!(
                            "could not start a worker thread ({e}); outputs may be partly written"
                        ),
                    ))
                }
            }
        }
        let last = last.map(work);
        let mut results = Vec::with_capacity(handles.len() + 1);
        for h in handles {
            results.push(
                h.join()
                    .map_err(|_| Failure::new(PelageStatus::Panic, "a worker thread panicked"))?,
            );
        }
        results.extend(last);
        Ok(results)
    })
}

/// Cuts `items` into consecutive parts of `lengths` (which sum to at most
/// its length).
pub(crate) fn cut_into<'a, T>(mut items: &'a mut [T], lengths: &[usize]) -> Vec<&'a mut [T]> {
    let mut parts = Vec::with_capacity(lengths.len());
    for &n in lengths {
        let (head, tail) = std::mem::take(&mut items).split_at_mut(n);
        parts.push(head);
        items = tail;
    }
    parts
}
