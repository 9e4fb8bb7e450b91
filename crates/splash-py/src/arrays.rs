//! numpy arrays in and out. Coordinates come in as (N, 3) arrays: borrowed without a copy when
//! their memory already is a `[Vec3]` (C-contiguous, aligned float32), copied once otherwise.
//! Results are moved into numpy: the arrays own the library's `Vec`s.

use ndarray::{Array1, Array2, ArrayView2};
use numpy::{
    PyArray1, PyArray2, PyArrayDescrMethods, PyArrayMethods, PyReadonlyArray2, PyUntypedArray,
    PyUntypedArrayMethods, dtype,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use splash_sph::{Attribute, Vec3};

/// (N, 3) coordinates as `[Vec3]`.
pub enum Points<'py> {
    /// A C-contiguous float32 array, read in place (numpy's borrow flag is held meanwhile).
    Borrowed(PyReadonlyArray2<'py, f32>),
    Owned(Vec<Vec3>),
}

impl Points<'_> {
    pub fn as_slice(&self) -> &[Vec3] {
        match self {
            Points::Borrowed(a) => bytemuck::cast_slice(a.as_slice().expect("checked in points()")),
            Points::Owned(v) => v,
        }
    }

    pub fn into_vec(self) -> Vec<Vec3> {
        match self {
            Points::Borrowed(_) => self.as_slice().to_vec(),
            Points::Owned(v) => v,
        }
    }
}

/// The (N, 3) floating-point array `obj` (or anything `numpy.asarray` makes one of) as
/// points; `what` names it in errors.
pub fn points<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<Points<'py>> {
    let array = floats(ndarray_of(obj)?, what)?;
    check_shape(&array, what, Some(3))?;
    if let Ok(a) = array.cast::<PyArray2<f32>>() {
        let a = a.try_readonly()?;
        let in_place = a.is_c_contiguous()
            && a.as_slice()
                .is_ok_and(|s| bytemuck::try_cast_slice::<f32, Vec3>(s).is_ok());
        if in_place {
            return Ok(Points::Borrowed(a));
        }
        return Ok(Points::Owned(rows(a.as_array())));
    }
    let a = array.cast::<PyArray2<f64>>()?.try_readonly()?;
    Ok(Points::Owned(rows(a.as_array().mapv(|v| v as f32).view())))
}

/// The (N,) floating-point array `obj` as a `Vec<f32>`.
pub fn scalars(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f32>> {
    let array = floats(ndarray_of(obj)?, what)?;
    check_shape(&array, what, None)?;
    if let Ok(a) = array.cast::<PyArray1<f32>>() {
        return Ok(a.try_readonly()?.as_array().to_vec());
    }
    let a = array.cast::<PyArray1<f64>>()?.try_readonly()?;
    Ok(a.as_array().iter().map(|&v| v as f32).collect())
}

/// The (N,) integer array `obj` as particle ids (copied): any integer dtype, each id in
/// [0, 2^32).
pub fn ids(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<u32>> {
    let array = ndarray_of(obj)?;
    check_shape(&array, what, None)?;
    if !matches!(array.dtype().kind(), b'i' | b'u') {
        return Err(wrong_dtype(&array, what, "integer"));
    }
    let wide: Bound<'_, PyArray1<i64>> = match array.cast::<PyArray1<i64>>() {
        Ok(a) => a.clone(),
        Err(_) => array.call_method1("astype", ("int64",))?.cast_into()?,
    };
    let wide = wide.try_readonly()?;
    wide.as_array()
        .iter()
        .enumerate()
        .map(|(i, &id)| {
            u32::try_from(id).map_err(|_| {
                PyValueError::new_err(format!("{what}[{i}] is {id}: ids must lie in [0, 2^32)"))
            })
        })
        .collect()
}

/// The (F, 3) uint32 array `obj` as triangles (copied).
pub fn triangles(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[u32; 3]>> {
    let array = ndarray_of(obj)?;
    check_shape(&array, what, Some(3))?;
    let a = array
        .cast::<PyArray2<u32>>()
        .map_err(|_| wrong_dtype(&array, what, "uint32"))?
        .try_readonly()?;
    Ok(a.as_array()
        .rows()
        .into_iter()
        .map(|r| [r[0], r[1], r[2]])
        .collect())
}

/// Whether `obj` is one value per particle (N,) rather than a vector per particle (N, 3).
pub fn is_scalar(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
    Ok(ndarray_of(obj)?.ndim() == 1)
}

fn rows(a: ArrayView2<'_, f32>) -> Vec<Vec3> {
    a.rows()
        .into_iter()
        .map(|r| Vec3::new(r[0], r[1], r[2]))
        .collect()
}

/// `array` when it holds native float32 or float64; other floating-point types (half or
/// extended precision, the other byte order) converted to float32 by numpy.
fn floats<'py>(
    array: Bound<'py, PyUntypedArray>,
    what: &str,
) -> PyResult<Bound<'py, PyUntypedArray>> {
    let py = array.py();
    let d = array.dtype();
    if d.is_equiv_to(&dtype::<f32>(py)) || d.is_equiv_to(&dtype::<f64>(py)) {
        return Ok(array);
    }
    if d.kind() != b'f' {
        return Err(wrong_dtype(&array, what, "floating-point"));
    }
    Ok(array.call_method1("astype", ("float32",))?.cast_into()?)
}

fn ndarray_of<'py>(obj: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyUntypedArray>> {
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return Ok(a.clone());
    }
    let numpy = obj.py().import("numpy")?;
    Ok(numpy.call_method1("asarray", (obj,))?.cast_into()?)
}

/// `columns`: Some(3) for (N, 3), None for (N,).
fn check_shape(a: &Bound<'_, PyUntypedArray>, what: &str, columns: Option<usize>) -> PyResult<()> {
    let ok = match columns {
        Some(c) => a.ndim() == 2 && a.shape()[1] == c,
        None => a.ndim() == 1,
    };
    if ok {
        return Ok(());
    }
    let expected = match columns {
        Some(c) => format!("(N, {c})"),
        None => "(N,)".to_string(),
    };
    Err(PyValueError::new_err(format!(
        "{what} must be an array of shape {expected}, got shape {:?}",
        a.shape()
    )))
}

fn wrong_dtype(a: &Bound<'_, PyUntypedArray>, what: &str, expected: &str) -> PyErr {
    PyValueError::new_err(format!(
        "{what} must hold {expected} values, got {}",
        a.dtype()
    ))
}

/// Moves points into a new (N, 3) float32 array.
pub fn points_array(py: Python<'_>, points: Vec<Vec3>) -> Bound<'_, PyArray2<f32>> {
    let n = points.len();
    let flat: Vec<f32> = bytemuck::cast_vec(points);
    let a = Array2::from_shape_vec((n, 3), flat).expect("3 floats per point");
    PyArray2::from_owned_array(py, a)
}

/// Moves triangles into a new (F, 3) uint32 array.
pub fn triangles_array(py: Python<'_>, triangles: Vec<[u32; 3]>) -> Bound<'_, PyArray2<u32>> {
    let n = triangles.len();
    let flat: Vec<u32> = bytemuck::cast_vec(triangles);
    let a = Array2::from_shape_vec((n, 3), flat).expect("3 corners per triangle");
    PyArray2::from_owned_array(py, a)
}

/// Moves values into a new (N,) float32 array.
pub fn scalars_array(py: Python<'_>, values: Vec<f32>) -> Bound<'_, PyArray1<f32>> {
    PyArray1::from_owned_array(py, Array1::from_vec(values))
}

/// One value or vector per particle of `array`, checked against the number of particles.
pub fn column(array: &Bound<'_, PyAny>, what: &str, particles: usize) -> PyResult<Attribute> {
    column_of(array, what, particles, "particles")
}

/// One value or vector per row of `array`, checked against `rows` (`of` names them in the
/// error: "particles", "active voxels").
pub fn column_of(
    array: &Bound<'_, PyAny>,
    what: &str,
    rows: usize,
    of: &str,
) -> PyResult<Attribute> {
    let (values, len) = if is_scalar(array)? {
        let v = scalars(array, what)?;
        let len = v.len();
        (Attribute::Scalar(v), len)
    } else {
        let v = points(array, what)?.into_vec();
        let len = v.len();
        (Attribute::Vector(v), len)
    };
    if len != rows {
        return Err(PyValueError::new_err(format!(
            "{what} has {len} values for {rows} {of}"
        )));
    }
    Ok(values)
}
