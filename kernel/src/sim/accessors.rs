//! What a front end reads of a simulation between steps (threads, lists, contact counts,
//! memory, the state's hash) and the switches it sets (a wall on or off).

use super::Simulation;
use crate::neighbor::PairList;
use glam::DVec3;

impl Simulation {
    /// Number of worker threads.
    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// The neighbour list (pairs and their contact history).
    pub fn pairs(&self) -> &PairList {
        &self.pairs
    }

    /// Number of pairs in the neighbour list.
    pub fn pair_count(&self) -> usize {
        self.pairs.len()
    }

    /// Switches wall `k` on or off (a mould removed, a box wall added): an inactive wall
    /// touches nothing. Its contacts end now; the neighbour lists are rebuilt at once.
    pub fn set_wall_active(&mut self, k: usize, active: bool) {
        if self.walls[k].active != active {
            self.walls[k].active = active;
            self.walls[k].force = DVec3::ZERO;
            self.walls[k].torque = DVec3::ZERO;
            self.rebuild();
        }
    }

    /// Contacts that currently carry force (pairs, then walls).
    pub fn contact_counts(&self) -> (usize, usize) {
        let pairs = self.pairs_carrying;
        let walls = self
            .walls_near
            .force
            .iter()
            .filter(|f| **f != DVec3::ZERO)
            .count();
        (pairs, walls)
    }

    /// Heap bytes held by particles, the pair list and the wall contacts.
    pub fn heap_bytes(&self) -> usize {
        self.particles.heap_bytes()
            + self.pairs.heap_bytes()
            + self.ref_position.capacity() * 24
            + self.kick_factor.capacity() * 16
            + (self.next_force.capacity() + self.next_torque.capacity()) * 24
            + self.walls_near.heap_bytes()
            + self.wall_shares.capacity() * 48
            // A B-tree entry (two ids and a time) with its share of the node, roughly.
            + self.retired_bonds.len() * 24
    }

    /// FNV-1a hash of the bits of every position, velocity and spin, in particle-id order:
    /// equal hashes mean bit-identical states.
    pub fn state_hash(&self) -> u64 {
        let mut h: u64 = 0xcbf29ce484222325;
        let p = &self.particles;
        // In id order, so the hash does not depend on how particles are currently sorted.
        let mut by_id: Vec<usize> = (0..p.len()).collect();
        by_id.sort_unstable_by_key(|&i| p.id[i]);
        for arr in [&p.position, &p.velocity, &p.angular_velocity] {
            for v in by_id.iter().map(|&i| &arr[i]) {
                for x in v.to_array() {
                    for b in x.to_bits().to_le_bytes() {
                        h ^= b as u64;
                        h = h.wrapping_mul(0x100000001b3);
                    }
                }
            }
        }
        h
    }
}
