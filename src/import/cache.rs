//! A decomposition cache on disk (`sdrs import --cache DIR`): V-HACD results
//! kept between imports, so that importing a robot again (another base,
//! other designable links, other masses) or a robot that shares meshes with
//! one imported before skips the decomposition, which is most of an import's
//! time.
//!
//! An entry is one file `DIR/<16 hex digits>.hulls`, named by the 64-bit
//! FNV-1a hash of its key and holding the key itself (format version, crate
//! version, every option the result depends on, and the mesh as placed in
//! its link: vertex bits and triangles) followed by the hulls (vertex and
//! plane bits, triangles). A file is used only when its stored key equals the
//! wanted one byte for byte, so a hash collision, a file from another
//! version or a damaged file is a miss, never a wrong result; a hit returns
//! exactly the hulls a new run would (V-HACD is deterministic: it runs
//! sequentially). Entries are written to a temporary file and renamed, so
//! imports running at the same time can share a directory.
//!
//! Only V-HACD is cached: CoACD runs in an external Python package whose
//! version this key cannot see, and the other decomposers are cheap.

use super::ImportOptions;
use super::decompose::{Decomposer, HullPoints};
use super::error::ImportError;
use super::mesh::TriMesh;
use super::polytope::Polytope;
use nalgebra::Vector3;
use std::path::{Path, PathBuf};

/// Layout version of the entry files; bump when the layout or the
/// decomposition's output changes without a crate version change.
const FORMAT: u32 = 1;
const MAGIC: &[u8; 12] = b"sdrs-hulls\0\0";

/// The cache directory of one import.
#[derive(Clone, Debug)]
pub struct DiskCache {
    dir: PathBuf,
}

impl DiskCache {
    /// Opens (creating it when missing) the cache directory `dir`.
    pub fn open(dir: &Path) -> Result<DiskCache, ImportError> {
        std::fs::create_dir_all(dir).map_err(|err| ImportError::Cache {
            path: dir.to_path_buf(),
            msg: format!("cannot create the cache directory: {err}"),
        })?;
        Ok(DiskCache {
            dir: dir.to_path_buf(),
        })
    }

    /// Whether results of `opts.decomposer` are cached.
    pub fn caches(decomposer: Decomposer) -> bool {
        decomposer == Decomposer::Vhacd
    }

    /// The stored hulls of `mesh` decomposed with `opts` and `max_hulls`, or
    /// `None` (no entry, or one whose key differs).
    pub fn load(
        &self,
        mesh: &TriMesh,
        opts: &ImportOptions,
        max_hulls: usize,
    ) -> Option<Vec<Polytope>> {
        let key = key_bytes(mesh, opts, max_hulls);
        let bytes = std::fs::read(self.entry(&key)).ok()?;
        let rest = bytes.strip_prefix(key.as_slice())?;
        decode_hulls(rest)
    }

    /// Stores `hulls` as the result for `mesh`, `opts` and `max_hulls`.
    pub fn store(
        &self,
        mesh: &TriMesh,
        opts: &ImportOptions,
        max_hulls: usize,
        hulls: &[Polytope],
    ) -> Result<(), ImportError> {
        let key = key_bytes(mesh, opts, max_hulls);
        let path = self.entry(&key);
        let mut bytes = key;
        encode_hulls(hulls, &mut bytes);
        let tmp = path.with_extension(format!("tmp{}", std::process::id()));
        let fail = |err: std::io::Error| ImportError::Cache {
            path: path.clone(),
            msg: format!("cannot write the cache entry: {err}"),
        };
        std::fs::write(&tmp, &bytes).map_err(fail)?;
        std::fs::rename(&tmp, &path).map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            fail(e)
        })
    }

    fn entry(&self, key: &[u8]) -> PathBuf {
        self.dir.join(format!("{:016x}.hulls", fnv1a(key)))
    }
}

/// FNV-1a, 64 bits (deterministic across runs and platforms).
fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

fn put_u64(out: &mut Vec<u8>, v: u64) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn put_vec3(out: &mut Vec<u8>, v: &Vector3<f64>) {
    for c in v.iter() {
        put_u64(out, c.to_bits());
    }
}

/// Every input the V-HACD result depends on, as bytes.
fn key_bytes(mesh: &TriMesh, opts: &ImportOptions, max_hulls: usize) -> Vec<u8> {
    let mut k = Vec::with_capacity(64 + 24 * mesh.vertices.len() + 24 * mesh.triangles.len());
    k.extend_from_slice(MAGIC);
    k.extend_from_slice(&FORMAT.to_le_bytes());
    let version = env!("CARGO_PKG_VERSION").as_bytes();
    put_u64(&mut k, version.len() as u64);
    k.extend_from_slice(version);
    k.extend_from_slice(opts.decomposer.name().as_bytes());
    k.push(match opts.hull_points {
        HullPoints::Voxels => 0,
        HullPoints::Mesh => 1,
    });
    put_u64(&mut k, max_hulls as u64);
    put_u64(&mut k, u64::from(opts.resolution));
    put_u64(&mut k, opts.threshold.to_bits());
    put_u64(&mut k, mesh.vertices.len() as u64);
    for v in &mesh.vertices {
        put_vec3(&mut k, v);
    }
    put_u64(&mut k, mesh.triangles.len() as u64);
    for t in &mesh.triangles {
        for &i in t {
            put_u64(&mut k, i as u64);
        }
    }
    k
}

fn encode_hulls(hulls: &[Polytope], out: &mut Vec<u8>) {
    put_u64(out, hulls.len() as u64);
    for h in hulls {
        put_u64(out, h.vertices.len() as u64);
        for v in &h.vertices {
            put_vec3(out, v);
        }
        put_u64(out, h.triangles.len() as u64);
        for t in &h.triangles {
            for &i in t {
                put_u64(out, i as u64);
            }
        }
        put_u64(out, h.planes.len() as u64);
        for (n, b) in &h.planes {
            put_vec3(out, n);
            put_u64(out, b.to_bits());
        }
    }
}

/// Reads little-endian words from an entry; `None` past the end.
struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn u64(&mut self) -> Option<u64> {
        let (head, rest) = self.0.split_first_chunk::<8>()?;
        self.0 = rest;
        Some(u64::from_le_bytes(*head))
    }
    fn f64(&mut self) -> Option<f64> {
        self.u64().map(f64::from_bits)
    }
    fn vec3(&mut self) -> Option<Vector3<f64>> {
        Some(Vector3::new(self.f64()?, self.f64()?, self.f64()?))
    }
    /// A count that the remaining bytes can hold at `size` bytes each.
    fn count(&mut self, size: usize) -> Option<usize> {
        let n = usize::try_from(self.u64()?).ok()?;
        (n.checked_mul(size)? <= self.0.len()).then_some(n)
    }
}

fn decode_hulls(bytes: &[u8]) -> Option<Vec<Polytope>> {
    let mut r = Reader(bytes);
    let n = r.count(24)?;
    let mut hulls = Vec::with_capacity(n);
    for _ in 0..n {
        let nv = r.count(24)?;
        let vertices = (0..nv).map(|_| r.vec3()).collect::<Option<Vec<_>>>()?;
        let nt = r.count(24)?;
        let mut triangles = Vec::with_capacity(nt);
        for _ in 0..nt {
            let t = [r.u64()?, r.u64()?, r.u64()?].map(|i| i as usize);
            if t.iter().any(|&i| i >= nv) {
                return None;
            }
            triangles.push(t);
        }
        let np = r.count(32)?;
        let planes = (0..np)
            .map(|_| Some((r.vec3()?, r.f64()?)))
            .collect::<Option<Vec<_>>>()?;
        hulls.push(Polytope {
            vertices,
            triangles,
            planes,
        });
    }
    (r.0.is_empty() && !hulls.is_empty()).then_some(hulls)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::polytope::convex_hull;

    fn cube_mesh(s: f64) -> TriMesh {
        let h = convex_hull(
            &(0..8)
                .map(|i| {
                    Vector3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64) * s
                })
                .collect::<Vec<_>>(),
        )
        .unwrap();
        TriMesh {
            vertices: h.vertices.clone(),
            triangles: h.triangles.clone(),
        }
    }

    fn same(a: &[Polytope], b: &[Polytope]) -> bool {
        let bits = |h: &Polytope| {
            let mut v = Vec::new();
            encode_hulls(std::slice::from_ref(h), &mut v);
            v
        };
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| bits(x) == bits(y))
    }

    #[test]
    fn an_entry_returns_the_stored_hulls_bit_for_bit_and_only_for_its_key() {
        let dir = std::env::temp_dir().join(format!("sdrs-cache-unit-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let cache = DiskCache::open(&dir).unwrap();
        let mesh = cube_mesh(0.1);
        let opts = ImportOptions::default();
        let hulls = vec![convex_hull(&mesh.vertices).unwrap()];
        assert!(cache.load(&mesh, &opts, 16).is_none());
        cache.store(&mesh, &opts, 16, &hulls).unwrap();
        assert!(same(&cache.load(&mesh, &opts, 16).unwrap(), &hulls));
        // Any input that changes the result is part of the key.
        assert!(cache.load(&mesh, &opts, 8).is_none());
        let mut nudged = mesh.clone();
        nudged.vertices[3].y = f64::from_bits(nudged.vertices[3].y.to_bits() + 1);
        assert!(cache.load(&nudged, &opts, 16).is_none());
        assert!(cache.load(&cube_mesh(0.2), &opts, 16).is_none());
        let o = |f: &dyn Fn(&mut ImportOptions)| {
            let mut o = ImportOptions::default();
            f(&mut o);
            o
        };
        assert!(cache.load(&mesh, &o(&|o| o.resolution = 32), 16).is_none());
        assert!(cache.load(&mesh, &o(&|o| o.threshold = 0.02), 16).is_none());
        assert!(
            cache
                .load(&mesh, &o(&|o| o.hull_points = HullPoints::Mesh), 16)
                .is_none()
        );
        // Options the decomposition does not read share the entry.
        assert!(cache.load(&mesh, &o(&|o| o.density = 500.0), 16).is_some());
        // A damaged entry (truncated, or with bytes appended) is a miss.
        let file = cache.entry(&key_bytes(&mesh, &opts, 16));
        let bytes = std::fs::read(&file).unwrap();
        std::fs::write(&file, &bytes[..bytes.len() - 5]).unwrap();
        assert!(cache.load(&mesh, &opts, 16).is_none());
        let mut longer = bytes.clone();
        longer.push(0);
        std::fs::write(&file, &longer).unwrap();
        assert!(cache.load(&mesh, &opts, 16).is_none());
        std::fs::write(&file, &bytes).unwrap();
        assert!(cache.load(&mesh, &opts, 16).is_some());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_cache_directory_that_cannot_be_created_is_an_error_naming_it() {
        let file = std::env::temp_dir().join(format!("sdrs-cache-file-{}", std::process::id()));
        std::fs::write(&file, b"not a directory").unwrap();
        let err = DiskCache::open(&file.join("sub")).unwrap_err().to_string();
        assert!(
            err.contains("sdrs-cache-file") && err.contains("cache directory"),
            "{err}"
        );
        let _ = std::fs::remove_file(&file);
    }

    #[test]
    fn fnv1a_matches_its_reference_values() {
        // Published FNV-1a 64 test vectors.
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x8594_4171_f739_67e8);
    }
}
