//! The seeds of Marching Slices (Rosenberg & Birdwell 2008, Sec. 4): from each particle's
//! nearest corner, a walk down in −z to the first corner outside; shared with the
//! surface-following baselines of the paper's Fig. 7 (`surface_following/`), so that every
//! approach starts from the same cubes.

use glam::{DVec3, IVec3};

/// The seed cubes of `local` (particle positions in cube units, by height), in the order
/// found: from each particle's nearest corner, down in −z until the field (`value`) is
/// outside; the cube above that corner is a seed. A particle's walk ends where the walk of the
/// particle below it in the same column began, or a reach (`reach_slabs` cubes) below it (the
/// paper's R_c: a particle found nothing there, one below it will). Where the nearest corner
/// is already outside, the particle's own cube is the seed.
///
/// In a block whose corners are 0..=`top` + 1 on each axis: particles above the block start
/// their walk at its top slice (a bubble in the top margin that dips into the block's cubes
/// is found only from the fluid above it); particles beside or below the block start none,
/// and no walk leaves it. Without `top`, the corners are unbounded.
pub fn particle_seeds(
    local: &[DVec3],
    reach_slabs: i32,
    top: Option<i32>,
    mut value: impl FnMut(IVec3) -> f32,
) -> Vec<IVec3> {
    let mut seeds = Vec::new();
    let mut starts: Vec<(IVec3, usize)> = local
        .iter()
        .enumerate()
        .map(|(i, q)| (q.round().as_ivec3(), i))
        .filter(|(c, _)| {
            top.is_none_or(|top| c.x >= 1 && c.y >= 1 && c.z >= 1 && c.x <= top && c.y <= top)
        })
        .map(|(c, i)| (top.map_or(c, |top| c.with_z(c.z.min(top))), i))
        .collect();
    starts.sort_unstable_by_key(|(c, _)| (c.y, c.x, c.z));
    let mut below: Option<(IVec3, bool)> = None;
    for (c, i) in starts {
        let same_column = below.filter(|(b, _)| b.x == c.x && b.y == c.y);
        if same_column.is_some_and(|(b, _)| b.z == c.z) {
            continue;
        }
        let start_inside = value(c) < 0.0;
        below = Some((c, start_inside));
        if !start_inside {
            match top {
                None => seeds.push(local[i].floor().as_ivec3()),
                Some(top) if local[i].z < f64::from(top) => seeds.push(
                    local[i]
                        .floor()
                        .as_ivec3()
                        .clamp(IVec3::ZERO, IVec3::splat(top)),
                ),
                Some(_) => {}
            }
            continue;
        }
        let floor = c.z - reach_slabs - 1;
        let floor = if top.is_some() { floor.max(0) } else { floor };
        for z in (floor..c.z).rev() {
            if let Some((b, inside)) = same_column
                && z == b.z
            {
                // The walk below starts here: it goes on from here, or this is its top.
                if !inside {
                    seeds.push(IVec3::new(c.x, c.y, z));
                }
                break;
            }
            if value(IVec3::new(c.x, c.y, z)) >= 0.0 {
                seeds.push(IVec3::new(c.x, c.y, z));
                break;
            }
        }
    }
    seeds
}
