//! `sdrs.Trajectory`: a run as numpy arrays.

use numpy::ndarray::{Array1, Array2, Array4};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray4};
use pyo3::prelude::*;
use sdrs::output::Trajectory;

/// A simulated run: times, coordinates, link poses and per-step contact and
/// Newton statistics, as numpy arrays (built on access). Row `k` of `q` is
/// the state after `k` steps (row 0 = the initial state).
#[pyclass(name = "Trajectory", module = "sdrs", frozen)]
pub struct PyTrajectory {
    pub traj: Trajectory,
    pub link_names: Vec<String>,
}

#[pymethods]
impl PyTrajectory {
    /// Times `t_k` (s), shape `(K+1,)`.
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        Array1::from_vec(self.traj.times.clone()).into_pyarray(py)
    }

    /// Reported coordinates `θ_k` (rad, m; free joints: position then an
    /// absolute rotation vector), shape `(K+1, ndof)`; the columns of the
    /// CLI's trajectory CSV after `t`.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let n = self.traj.names.len();
        let flat: Vec<f64> = self
            .traj
            .states
            .iter()
            .flat_map(|s| s.iter().copied())
            .collect();
        Array2::from_shape_vec((self.traj.states.len(), n), flat)
            .expect("rows of equal length")
            .into_pyarray(py)
    }

    /// Coordinate names (the CSV header after `t`).
    #[getter]
    fn names(&self) -> Vec<String> {
        self.traj.names.clone()
    }

    /// Link names (`robot/link`), the second axis of `poses`.
    #[getter]
    fn link_names(&self) -> Vec<String> {
        self.link_names.clone()
    }

    /// Link poses `A_i = [R | p]` (world), shape `(K+1, nlinks, 3, 4)`.
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray4<f64>> {
        let k = self.traj.poses.len();
        let nl = self.link_names.len();
        let mut flat = Vec::with_capacity(k * nl * 12);
        for step in &self.traj.poses {
            for a in step {
                for r in 0..3 {
                    for c in 0..4 {
                        flat.push(a[(r, c)]);
                    }
                }
            }
        }
        Array4::from_shape_vec((k, nl, 3, 4), flat)
            .expect("poses of every link")
            .into_pyarray(py)
    }

    /// Hull pairs in contact (non-zero barrier potential) after each step,
    /// shape `(K,)`.
    #[getter]
    fn contact_pairs<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let v: Vec<i64> = self
            .traj
            .diagnostics
            .iter()
            .map(|d| d.contact_pairs as i64)
            .collect();
        Array1::from_vec(v).into_pyarray(py)
    }

    /// Smallest distance between candidate hull pairs after each step (m;
    /// `inf` without candidates), shape `(K,)`.
    #[getter]
    fn min_distance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let v: Vec<f64> = self
            .traj
            .diagnostics
            .iter()
            .map(|d| d.min_distance)
            .collect();
        Array1::from_vec(v).into_pyarray(py)
    }

    /// Newton iterations of each step, shape `(K,)`.
    #[getter]
    fn newton_iterations<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let v: Vec<i64> = self
            .traj
            .diagnostics
            .iter()
            .map(|d| d.newton.iters as i64)
            .collect();
        Array1::from_vec(v).into_pyarray(py)
    }

    /// The trajectory CSV exactly as `sdrs simulate --out` writes it (shortest
    /// round-trip number formatting, so `float()` of each field gives `q`
    /// bitwise).
    fn to_csv(&self) -> String {
        self.traj.to_csv()
    }

    fn __len__(&self) -> usize {
        self.traj.times.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Trajectory({} states, {} coordinates, {} links)",
            self.traj.times.len(),
            self.traj.names.len(),
            self.link_names.len()
        )
    }
}
