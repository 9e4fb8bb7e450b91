//! VDB output of isosurfaces with attributes: each attribute grid holds, at each active voxel,
//! the particles' value at that voxel's place, whatever the turn upright.

use glam::Vec3;

use super::frame::FramePipeline;
use super::{FrameOutcome, Progress};
use crate::config::Config;
use crate::io::{Attribute, MeshFormat, UpAxis};
use crate::iso::{Derived, IsoRequest};
use crate::length::Length;

struct Quiet;

impl Progress for Quiet {
    fn frame_done(&mut self, _o: &FrameOutcome, _done: usize, _total: usize) {}
}

/// A lattice ball of radius 1.2 (spacing 0.1) whose particles carry `a` = their distance to
/// the centre `c` and the velocity (1, 2, 3): its isosurface a = 0.6 is a sphere well inside
/// the particles, written as VDB with `a` and the velocity as grids. At every active voxel
/// `p`, the level set is |p − c| − 0.6 within a quarter of a voxel and the grid `a` is
/// |p − c| within a fifth (the kernel sums of a lattice are 1 within about 0.3 %), turned
/// upright or not; the velocity grid turns with the grid. A grid sampled a voxel off, or at
/// the voxels' places after the turn, is off by a voxel (0.05) or more.
#[test]
fn an_isosurfaces_attribute_grids_lie_on_its_voxels() {
    let dir = std::env::temp_dir().join(format!("splash-iso-vdb-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let input = dir.join("ball.csv");
    let centre = Vec3::new(0.13, -0.08, 0.05);
    let mut text = String::from("x,y,z,a,vx,vy,vz\n");
    for x in -12..=12 {
        for y in -12..=12 {
            for z in -12..=12 {
                let p = Vec3::new(x as f32, y as f32, z as f32) * 0.1;
                if p.length() <= 1.2 {
                    let a = (p - centre).length();
                    text += &format!("{},{},{},{a},1,2,3\n", p.x, p.y, p.z);
                }
            }
        }
    }
    std::fs::write(&input, text).unwrap();
    for up_axis in [None, Some(UpAxis::Z)] {
        let mut config = Config {
            spacing: Some(0.1),
            cell: Length::parse("r/2").unwrap(),
            ..Config::default()
        };
        config.output.attributes = vec!["a".into(), "velocity".into()];
        config.output.up_axis = up_axis;
        let request = IsoRequest {
            attribute: "a".into(),
            derived: Derived::Value,
            level: 0.6,
        };
        let mut pipeline =
            FramePipeline::new(None, MeshFormat::Vdb, config, Some(request)).unwrap();
        let loaded = pipeline.loader().load(&input).unwrap();
        let made = pipeline.make(&input, loaded, &mut Quiet).unwrap();
        let (level_set, named) = made.level_set_and_grids();
        let [
            (a_name, Attribute::Scalar(a)),
            (v_name, Attribute::Vector(v)),
        ] = named
        else {
            panic!("grids a and velocity")
        };
        assert_eq!((a_name.as_str(), v_name.as_str()), ("a", "velocity"));
        let voxels = level_set.values.len();
        assert!(voxels > 1000 && a.len() == voxels && v.len() == voxels);
        let mut upright = [centre];
        let turned = match up_axis {
            Some(axis) => {
                axis.rotate(&mut upright);
                let mut v = [Vec3::new(1.0, 2.0, 3.0)];
                axis.rotate(&mut v);
                v[0]
            }
            None => Vec3::new(1.0, 2.0, 3.0),
        };
        let (mut phi_off, mut a_off, mut v_off) = (0.0f32, 0.0f32, 0.0f32);
        for (k, p) in level_set.positions().into_iter().enumerate() {
            let distance = (p - upright[0]).length();
            phi_off = phi_off.max((level_set.values[k] - (distance - 0.6)).abs());
            a_off = a_off.max((a[k] - distance).abs());
            v_off = v_off.max((v[k] - turned).length());
        }
        let voxel = level_set.voxel;
        assert!(
            phi_off < 0.25 * voxel,
            "{up_axis:?}: level set off by {phi_off}"
        );
        assert!(a_off < 0.2 * voxel, "{up_axis:?}: grid a off by {a_off}");
        assert!(
            v_off < 0.01 * turned.length(),
            "{up_axis:?}: velocity off by {v_off}"
        );
        eprintln!("{up_axis:?}: {voxels} voxels, off by {phi_off}, {a_off}, {v_off}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
