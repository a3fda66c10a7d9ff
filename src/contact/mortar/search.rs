//! Candidate master facets of a slave facet: an R-tree (rstar) of the master facets'
//! bounding boxes, queried with the slave facet's box grown by the search radius
//! (O(log n) per query, O(n log n) to build).

use super::surface::Surface;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

/// The master facets' bounding boxes in an R-tree.
pub struct MasterTree {
    tree: RTree<GeomWithData<Rectangle<[f64; 3]>, usize>>,
}

impl MasterTree {
    /// The tree of all facets of `master`.
    pub fn new(master: &Surface) -> Self {
        let boxes = (0..master.n_facets())
            .map(|f| {
                let (lo, hi) = master.bbox(f);
                GeomWithData::new(Rectangle::from_corners(lo, hi), f)
            })
            .collect();
        MasterTree {
            tree: RTree::bulk_load(boxes),
        }
    }

    /// The master facets (sorted) whose boxes meet the box (`lo`, `hi`) grown by `radius` on
    /// every side.
    pub fn candidates(&self, lo: [f64; 3], hi: [f64; 3], radius: f64) -> Vec<usize> {
        let grow = |x: [f64; 3], s: f64| x.map(|v| v + s * radius);
        let env = AABB::from_corners(grow(lo, -1.0), grow(hi, 1.0));
        let mut found: Vec<usize> = self
            .tree
            .locate_in_envelope_intersecting(&env)
            .map(|g| g.data)
            .collect();
        found.sort_unstable();
        found
    }
}
