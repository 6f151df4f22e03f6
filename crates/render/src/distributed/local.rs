//! [`Collective`] over threads and channels: N ranks in one process, for tests and for
//! checking the distributed loop without MPI.

use std::sync::mpsc::{Receiver, Sender, channel};

use super::Collective;

/// Builds the ranks of an in-process communicator.
pub struct LocalRanks;

/// One rank of an in-process communicator; move it into its thread.
pub struct LocalRank {
    rank: usize,
    size: usize,
    /// Rank 0: one receiver per rank (index = sender; index 0 unused).
    from_ranks: Vec<Receiver<Vec<u8>>>,
    /// Ranks other than 0: the channel to rank 0.
    to_root: Option<Sender<Vec<u8>>>,
    /// Rank 0: one sender per other rank for broadcasts (index = rank − 1).
    broadcast_to: Vec<Sender<Vec<u8>>>,
    /// Ranks other than 0: broadcasts from rank 0.
    broadcast_from: Option<Receiver<Vec<u8>>>,
}

impl LocalRanks {
    /// `size` connected ranks (at least 1), rank 0 first.
    pub fn connect(size: usize) -> Vec<LocalRank> {
        let size = size.max(1);
        let mut root = LocalRank {
            rank: 0,
            size,
            from_ranks: Vec::new(),
            to_root: None,
            broadcast_to: Vec::new(),
            broadcast_from: None,
        };
        let mut others = Vec::new();
        let (_, unused) = channel();
        root.from_ranks.push(unused);
        for rank in 1..size {
            let (to_root, from_rank) = channel();
            let (broadcast_to, broadcast_from) = channel();
            root.from_ranks.push(from_rank);
            root.broadcast_to.push(broadcast_to);
            others.push(LocalRank {
                rank,
                size,
                from_ranks: Vec::new(),
                to_root: Some(to_root),
                broadcast_to: Vec::new(),
                broadcast_from: Some(broadcast_from),
            });
        }
        let mut ranks = vec![root];
        ranks.extend(others);
        ranks
    }
}

impl Collective for LocalRank {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn send_to_root(&self, bytes: &[u8]) -> Result<(), String> {
        let sender = self.to_root.as_ref().ok_or("rank 0 cannot send to itself")?;
        sender.send(bytes.to_vec()).map_err(|_| format!("rank {}: rank 0 has gone", self.rank))
    }

    fn receive_from(&self, rank: usize) -> Result<Vec<u8>, String> {
        let receiver = self
            .from_ranks
            .get(rank)
            .filter(|_| rank > 0)
            .ok_or_else(|| format!("rank {} cannot receive from rank {rank}", self.rank))?;
        receiver.recv().map_err(|_| format!("rank {rank} has gone"))
    }

    fn broadcast(&self, bytes: Vec<u8>) -> Result<Vec<u8>, String> {
        match &self.broadcast_from {
            Some(receiver) => receiver.recv().map_err(|_| format!("rank {}: rank 0 has gone", self.rank)),
            None => {
                for (index, sender) in self.broadcast_to.iter().enumerate() {
                    sender.send(bytes.clone()).map_err(|_| format!("rank {} has gone", index + 1))?;
                }
                Ok(bytes)
            }
        }
    }
}
