//! `vcm render` under `mpirun` (cargo feature `mpi`): the session spread over the MPI ranks
//! ([`session::render_on`], [`render::distributed`]), with the image of one process bit for
//! bit. Every rank parses the same command line, so the ranks' settings cannot differ. Rank 0
//! alone prints notices, progress and the summary and writes the outputs; an error on any rank
//! ends every rank with it (exit code 2), printed once by rank 0. Design:
//! `docs/distributed.md`.

use std::sync::atomic::AtomicBool;

use anyhow::{Result, anyhow};
use mpi::Threading;
use mpi::topology::SimpleCommunicator;
use mpi::traits::{Communicator, Destination, Root, Source};
use render::distributed::Collective;
use session::Notice;

/// Tag of a message with bytes.
const DATA: i32 = 0;
/// Tag of an empty message (sent as one ignored byte).
const EMPTY: i32 = 1;

/// [`Collective`] over an MPI communicator (rank 0 is the root). MPI is only called from the
/// main thread (the render's worker threads never call it), hence `Threading::Funneled`.
struct World(SimpleCommunicator);

impl Collective for World {
    fn rank(&self) -> usize {
        self.0.rank() as usize
    }

    fn size(&self) -> usize {
        self.0.size() as usize
    }

    fn send_to_root(&self, bytes: &[u8]) -> Result<(), String> {
        // An empty slice's pointer is 1, which Open MPI reads as MPI_IN_PLACE: an empty
        // message travels as one byte with tag EMPTY.
        let root = self.0.process_at_rank(0);
        if bytes.is_empty() {
            root.send_with_tag(&[0u8][..], EMPTY);
        } else {
            root.send_with_tag(bytes, DATA);
        }
        Ok(())
    }

    fn receive_from(&self, rank: usize) -> Result<Vec<u8>, String> {
        let rank = i32::try_from(rank).map_err(|_| format!("no MPI rank {rank}"))?;
        let (bytes, status) = self.0.process_at_rank(rank).receive_vec::<u8>();
        Ok(if status.tag() == EMPTY { Vec::new() } else { bytes })
    }

    fn broadcast(&self, mut bytes: Vec<u8>) -> Result<Vec<u8>, String> {
        let root = self.0.process_at_rank(0);
        let mut len = bytes.len() as u64;
        root.broadcast_into(&mut len);
        let len = usize::try_from(len).map_err(|_| format!("a broadcast of {len} bytes"))?;
        bytes.resize(len, 0);
        if len > 0 {
            root.broadcast_into(&mut bytes[..]);
        }
        Ok(bytes)
    }
}

/// Prints rank 0's notices (progress ones unless quiet) and installs the interrupt handler
/// on every rank.
struct RankObserver {
    root: bool,
    quiet: bool,
}

impl session::Observer for RankObserver {
    fn notice(&mut self, notice: Notice) {
        if self.root && !(self.quiet && matches!(notice, Notice::Progress(_))) {
            eprintln!("{notice}");
        }
    }

    fn starting(&mut self) {
        crate::install_interrupt_handler();
    }
}

/// Runs `request` on every rank of `mpirun`; rank 0 prints the summary. An error ends every
/// rank with exit code 2, printed by rank 0 alone, before MPI is finalised.
pub fn render(request: &session::Request, stop: &'static AtomicBool, quiet: bool) -> Result<()> {
    let (universe, _) = mpi::initialize_with_threading(Threading::Funneled)
        .ok_or_else(|| anyhow!("cannot initialise MPI (was it initialised already?)"))?;
    let world = World(universe.world());
    let root = world.rank() == 0;
    let mut observer = RankObserver { root, quiet };
    let request = session::Request { progress: request.progress && root, ..request.clone() };
    let outcome = session::render_on(&request, Some(stop), &mut observer, Some(&world));
    // An error is printed before MPI_Finalize (collective): a rank that exits with code 2 makes
    // mpirun end the job, and it can only get there after rank 0 has written the message.
    if let (Err(error), true) = (&outcome, root) {
        eprintln!("error: {error:#}");
        let _ = std::io::Write::flush(&mut std::io::stderr());
    }
    drop(world);
    drop(universe);
    match outcome {
        Ok(outcome) => {
            if root {
                eprintln!("{}", outcome.summary);
            }
            Ok(())
        }
        Err(_) => std::process::exit(2),
    }
}
