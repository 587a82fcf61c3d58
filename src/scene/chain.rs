//! The rotating-chain generator (paper, `evaluation.tex`: "four rotating
//! chains … each chain has # ball joints each having 2 degrees of freedom").

use super::schema::{ChainSpec, HullSpec, JointSpec, JointType, LinkSpec, Origin};

/// Expands a chain into links `link0 … link{n−1}` with joints `j0 …`; link
/// `i` is a box of `width × width × length` hanging from its joint along −z,
/// and link `i+1` is attached at the far end of link `i`.
pub fn expand(spec: &ChainSpec) -> Vec<LinkSpec> {
    let (l, w) = (spec.link_length, spec.link_width);
    (0..spec.links)
        .map(|i| LinkSpec {
            name: format!("link{i}"),
            parent: (i > 0).then(|| format!("link{}", i - 1)),
            joint: JointSpec {
                name: Some(format!("j{i}")),
                kind: spec.joint,
                axis: (spec.joint == JointType::Revolute).then_some([0.0, 1.0, 0.0]),
                axes: (spec.joint == JointType::Ball).then_some([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
                origin: Origin {
                    xyz: if i == 0 { [0.0; 3] } else { [0.0, 0.0, -l] },
                    rpy: [0.0; 3],
                },
                limit: None,
                mimic: None,
            },
            mass: Some(spec.link_mass),
            vertex_mass: None,
            mass_model: None,
            hulls: vec![HullSpec::cuboid([w, w, l], [0.0, 0.0, -l / 2.0])],
            collide: true,
            surface_mesh: None,
        })
        .collect()
}
