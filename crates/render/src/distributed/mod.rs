//! One progressive render spread over ranks (processes, e.g. MPI ranks), bit-identical to one
//! process. Design and costs: `docs/distributed.md`.
//!
//! An iteration is a function of the seed and its global index only ([`crate::driver`]), so
//! ranks can render any iterations; the film's f64 sums depend on the order of addition, so
//! rank 0 adds every iteration in index order. In round k, rank r renders iteration
//! `base + r` (base = first index of the round, advancing by the rank count) when the budget
//! allows, sends its [`IterationResult`](crate::progressive::IterationResult) (or none) with
//! its stop flag to rank 0, which adds them in rank order — the order of one process — and
//! broadcasts whether to continue.
//!
//! The transport is the [`Collective`] trait, with no MPI dependency here: the command line's
//! `mpi` feature implements it over MPI, [`LocalRanks`] over threads and channels (tests).

mod local;
pub mod wire;
#[cfg(test)]
mod wire_tests;

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

pub use local::{LocalRank, LocalRanks};
use wire::Decision;

use crate::driver::{Budget, RenderSettings, SaveFilm};
use crate::progressive::{Progressive, progress_bar};

/// The point-to-point and broadcast operations a distributed render needs. Every rank calls the
/// same operations in the same order; rank 0 is the root.
pub trait Collective {
    /// This rank's index, 0..size.
    fn rank(&self) -> usize;
    /// The number of ranks (at least 1).
    fn size(&self) -> usize;
    /// Sends `bytes` to rank 0 (called on ranks other than 0).
    fn send_to_root(&self, bytes: &[u8]) -> Result<(), String>;
    /// Receives the next message rank `rank` sent to rank 0 (called on rank 0).
    fn receive_from(&self, rank: usize) -> Result<Vec<u8>, String>;
    /// Broadcasts rank 0's `bytes`: rank 0 passes its bytes and gets them back, every other
    /// rank passes anything and gets rank 0's.
    fn broadcast(&self, bytes: Vec<u8>) -> Result<Vec<u8>, String>;
}

/// Makes every rank end with the same outcome: when `result` is an error on any rank, every
/// rank returns the first failing rank's error (named "rank r: ..." when there are several
/// ranks); otherwise each rank keeps its value. One gather and one broadcast: never a hang
/// while every rank calls it.
pub fn agree<T>(comm: &dyn Collective, result: Result<T, String>) -> Result<T, String> {
    let mine = match &result {
        Ok(_) => Vec::new(),
        Err(message) => {
            let mut bytes = message.as_bytes().to_vec();
            bytes.insert(0, 1);
            bytes
        }
    };
    let first_error = if comm.rank() == 0 {
        let mut first: Option<Vec<u8>> = None;
        for rank in 0..comm.size() {
            let bytes = if rank == 0 { mine.clone() } else { comm.receive_from(rank)? };
            if first.is_none() && !bytes.is_empty() {
                let text = String::from_utf8_lossy(&bytes[1..]);
                let named = if comm.size() > 1 { format!("rank {rank}: {text}") } else { text.into_owned() };
                first = Some(named.into_bytes());
            }
        }
        comm.broadcast(first.unwrap_or_default())?
    } else {
        comm.send_to_root(&mine)?;
        comm.broadcast(Vec::new())?
    };
    match (result, first_error.is_empty()) {
        (Ok(value), true) => Ok(value),
        (Err(own), true) => Err(own),
        (_, false) => Err(String::from_utf8_lossy(&first_error).into_owned()),
    }
}

/// The distributed counterpart of [`crate::progressive::run_budget`], called by every rank with
/// its own [`Progressive`] of the same scene and settings. Rank 0's film (a resumed film on
/// rank 0 only) receives every iteration in index order; the other ranks' films stay empty.
/// `Budget::Iterations(n)` ends when the film holds n iterations; `Budget::Time` after the
/// first round that ends past the limit (whole iterations, at least one round); any rank's
/// `stop` flag, read before it renders, ends the render after the round (iterations are added
/// up to the first rank that rendered none, so the film holds consecutive iterations).
/// `checkpoint` (used on rank 0 only) saves like `run_budget`'s. Returns whether a stop flag
/// ended the render; every rank returns rank 0's error when rank 0 fails.
pub fn run_distributed(
    progressive: &mut Progressive,
    settings: &RenderSettings,
    stop: Option<&AtomicBool>,
    mut checkpoint: Option<(Duration, SaveFilm)>,
    comm: &dyn Collective,
) -> Result<bool, String> {
    let (rank, size) = (comm.rank(), comm.size());
    let root = rank == 0;
    let start = Instant::now();
    let mut last_checkpoint = Instant::now();
    let first = comm.broadcast(progressive.next_iteration().to_le_bytes().to_vec())?;
    let mut base = u64::from_le_bytes(
        first.as_slice().try_into().map_err(|_| format!("rank 0 sent a first iteration of {} bytes", first.len()))?,
    );
    let progress = if root { progress_bar(settings) } else { None };
    loop {
        let round_start = Instant::now();
        let iteration = base + rank as u64;
        let stopped = stop.is_some_and(|s| s.load(Ordering::Relaxed));
        let within = match settings.budget {
            Budget::Iterations(n) => iteration < n,
            Budget::Time(_) => true,
        };
        let result = (within && !stopped).then(|| progressive.render_iteration(iteration));
        let message = wire::encode_message(stopped, result.as_ref());
        drop(result);
        let decision = if root {
            let mut decision = match gather(progressive, comm, message) {
                Ok(true) => Decision::Stop(true),
                Ok(false) => match settings.budget {
                    Budget::Iterations(n) if progressive.next_iteration() >= n => Decision::Stop(false),
                    Budget::Time(limit) if start.elapsed() >= limit => Decision::Stop(false),
                    _ => Decision::Continue(progressive.next_iteration()),
                },
                Err(error) => Decision::Failed(error),
            };
            progressive.add_elapsed(round_start.elapsed());
            if let (Decision::Continue(_), Some((every, save))) = (&decision, &mut checkpoint)
                && last_checkpoint.elapsed() >= *every
            {
                if let Err(error) = save(progressive.film()) {
                    decision = Decision::Failed(error);
                }
                last_checkpoint = Instant::now();
            }
            if let Some(bar) = &progress {
                match settings.budget {
                    Budget::Iterations(_) => bar.set_position(progressive.iterations()),
                    Budget::Time(_) => {
                        bar.set_position(start.elapsed().as_millis() as u64);
                        bar.set_message(format!("{} it, {size} ranks", progressive.iterations()));
                    }
                }
            }
            comm.broadcast(wire::encode_decision(&decision))?;
            decision
        } else {
            comm.send_to_root(&message)?;
            progressive.add_elapsed(round_start.elapsed());
            wire::decode_decision(&comm.broadcast(Vec::new())?)?
        };
        match decision {
            Decision::Continue(next) => base = next,
            Decision::Stop(interrupted) => {
                if let Some(bar) = progress {
                    bar.finish_and_clear();
                }
                if let (true, Some((_, save))) = (root, &mut checkpoint) {
                    save(progressive.film())?;
                }
                return Ok(interrupted);
            }
            Decision::Failed(error) if root => return Err(error),
            Decision::Failed(error) => return Err(format!("rank 0 failed: {error}")),
        }
    }
}

/// Rank 0's half of a round: adds its own message's result and every other rank's, in rank
/// order, up to the first rank without one. Returns whether any rank's stop flag was set.
fn gather(progressive: &mut Progressive, comm: &dyn Collective, own: Vec<u8>) -> Result<bool, String> {
    let mut any_stop = false;
    let mut contiguous = true;
    let mut first_error = None;
    for rank in 0..comm.size() {
        // Every message is received even after an error, so no rank is left sending.
        let bytes = if rank == 0 { own.clone() } else { comm.receive_from(rank)? };
        if first_error.is_some() {
            continue;
        }
        match wire::decode_message(&bytes, rank) {
            Ok((stop, result)) => {
                any_stop |= stop;
                match result {
                    Some(result) if contiguous => {
                        if let Err(error) = progressive.add_result(&result) {
                            first_error = Some(error);
                        }
                    }
                    Some(_) => {}
                    None => contiguous = false,
                }
            }
            Err(error) => first_error = Some(error),
        }
    }
    match first_error {
        Some(error) => Err(error),
        None => Ok(any_stop),
    }
}
