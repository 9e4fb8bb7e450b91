//! The seeds of Marching Slices (Rosenberg & Birdwell 2008, Sec. 4): from each particle's
//! nearest corner, a walk down in −z to the first corner outside; shared with the
//! surface-following baselines of the paper's Fig. 7 (`surface_following/`), so that every
//! approach starts from the same cubes.

use glam::{DVec3, IVec3};

/// The seed cubes of the `count` particles at `local(i)` (positions in cube units), in the
/// order of the walks by column: from each particle's nearest corner, down in −z until the
/// field (`value`) is outside; the cube above that corner is a seed. A particle's walk ends
/// where the walk of the particle below it in the same column began, or a reach
/// (`reach_slabs` cubes) below it (the paper's R_c: a particle found nothing there, one below
/// it will). Where the nearest corner is already outside, the particle's own cube is the seed.
///
/// In a block whose corners are 0..=`top` + 1 on each axis: particles above the block start
/// their walk at its top slice (a bubble in the top margin that dips into the block's cubes
/// is found only from the fluid above it); particles beside or below the block start none,
/// and no walk leaves it. Without `top`, the corners are unbounded.
///
/// The walks go down together, slice by slice, so that `value` is asked for the corners of
/// one slice after another from the top (the slices engine's lookup cache keeps only a window
/// of slices); the seeds come out in the order of the walks by column all the same.
pub fn particle_seeds(
    count: usize,
    local: impl Fn(usize) -> DVec3,
    reach_slabs: i32,
    top: Option<i32>,
    mut value: impl FnMut(IVec3) -> f32,
) -> Vec<IVec3> {
    let mut starts: Vec<(IVec3, usize)> = (0..count)
        .map(|i| (local(i).round().as_ivec3(), i))
        .filter(|(c, _)| {
            top.is_none_or(|top| c.x >= 1 && c.y >= 1 && c.z >= 1 && c.x <= top && c.y <= top)
        })
        .map(|(c, i)| (top.map_or(c, |top| c.with_z(c.z.min(top))), i))
        .collect();
    starts.sort_unstable_by_key(|(c, _)| (c.y, c.x, c.z));
    // A walk from the corner of the walk before it would repeat it.
    starts.dedup_by_key(|s| s.0);
    // The walk below walk k, in the same column, begins at this corner.
    let below = |k: usize| {
        let c = starts[k].0;
        (k > 0 && starts[k - 1].0.truncate() == c.truncate()).then(|| starts[k - 1].0)
    };
    let floor = |c: IVec3| {
        let z = c.z - reach_slabs - 1;
        if top.is_some() { z.max(0) } else { z }
    };
    let Some(highest) = starts.iter().map(|s| s.0.z).max() else {
        return Vec::new();
    };
    let lowest = starts.iter().map(|s| floor(s.0)).min().unwrap_or(highest);
    let mut by_height: Vec<u32> = (0..starts.len() as u32).collect();
    by_height.sort_by_key(|&k| std::cmp::Reverse(starts[k as usize].0.z));
    let mut inside = vec![false; starts.len()];
    let mut seeds: Vec<Option<IVec3>> = vec![None; starts.len()];
    let (mut walks, mut begun) = (Vec::new(), Vec::new());
    let mut next = by_height.iter().peekable();
    for z in (lowest..=highest).rev() {
        // The walks beginning here, then the steps down to here of those begun above, which
        // end here if the walk below begins here.
        while let Some(&k) = next.next_if(|&&k| starts[k as usize].0.z == z) {
            let (c, i) = starts[k as usize];
            inside[k as usize] = value(c) < 0.0;
            if inside[k as usize] {
                begun.push(k);
                continue;
            }
            let q = local(i);
            match top {
                None => seeds[k as usize] = Some(q.floor().as_ivec3()),
                Some(top) if q.z < f64::from(top) => {
                    let own = q.floor().as_ivec3().clamp(IVec3::ZERO, IVec3::splat(top));
                    seeds[k as usize] = Some(own);
                }
                Some(_) => {}
            }
        }
        walks.retain(|&k| {
            let k = k as usize;
            let c = starts[k].0;
            if z < floor(c) {
                return false;
            }
            if let Some(b) = below(k)
                && z == b.z
            {
                // The walk below starts here: it goes on from here, or this is its top.
                if !inside[k - 1] {
                    seeds[k] = Some(c.with_z(z));
                }
                return false;
            }
            if value(c.with_z(z)) >= 0.0 {
                seeds[k] = Some(c.with_z(z));
                return false;
            }
            true
        });
        walks.append(&mut begun);
    }
    seeds.into_iter().flatten().collect()
}
