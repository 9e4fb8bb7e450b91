//! The `Config` of a call: a TOML file or a dict, with the keyword arguments on top, as the
//! command line puts its flags on top of `--config`.

use std::path::PathBuf;

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use splash_sph::mesh::VolumeScope;
use splash_sph::{Bytes, Config, Engine, Length, MeshFormat, Normals, OutputConfig, UpAxis};

use crate::errors::to_py;

/// Defines a `#[pyfunction]` that takes the keyword arguments overriding the configuration,
/// named and typed here only (the options of `splash_sph::OPTIONS`; the command line's
/// `options_table` test checks the stub against that table): after the function's own
/// parameters (`signature` gives their part of the Python signature, up to and with the `*`)
/// come `cell` … `volume_scope`, then the `then` parameters (keyword arguments defaulting to
/// None), then, with `files`, the options of files and sequences: `particle_aabb`, `format`,
/// `up_axis`, `attributes` (names) and `temporal`. The body sees them as `$options`, an
/// [`Overrides`] whose `spacing` is None (each function places that argument itself:
/// positional in `reconstruct`).
macro_rules! options_function {
    (
        $(#[$meta:meta])*
        fn $name:ident<'py>($($param:ident: $ty:ty),* $(,)?)
            signature($($sig:tt)*) then($($then:ident: $then_ty:ty),*) files
            -> $ret:ty, |$options:ident| $body:block
    ) => {
        options_function!(@emit $(#[$meta])* $name ($($param: $ty),*) ($($sig)*)
            ($($then: $then_ty),*)
            (particle_aabb: Option<Vec<f32>>, format: Option<String>, up_axis: Option<String>,
             attributes: Option<Bound<'py, PyAny>>, temporal: Option<bool>) $ret, $options $body);
    };
    (
        $(#[$meta:meta])*
        fn $name:ident<'py>($($param:ident: $ty:ty),* $(,)?)
            signature($($sig:tt)*) then($($then:ident: $then_ty:ty),*)
            -> $ret:ty, |$options:ident| $body:block
    ) => {
        options_function!(@emit $(#[$meta])* $name ($($param: $ty),*) ($($sig)*)
            ($($then: $then_ty),*) () $ret, $options $body);
    };
    (@emit $(#[$meta:meta])* $name:ident ($($param:ident: $ty:ty),*) ($($sig:tt)*)
        ($($then:ident: $then_ty:ty),*) ($($files:ident: $files_ty:ty),*) $ret:ty,
        $options:ident $body:block) => {
        $(#[$meta])*
        #[allow(clippy::too_many_arguments)]
        #[pyo3::pyfunction]
        #[pyo3(signature = ($($sig)* cell=None, field=None, engine=None, normals=None,
            correct=None, block=None, threads=None, max_memory=None, raw=None, decimate=None,
            min_component=None, mesh_aabb=None, volume_scope=None $(, $then=None)*
            $(, $files=None)*))]
        pub fn $name<'py>(
            $($param: $ty,)*
            cell: Option<Bound<'py, PyAny>>,
            field: Option<String>,
            engine: Option<String>,
            normals: Option<String>,
            correct: Option<i64>,
            block: Option<i64>,
            threads: Option<i64>,
            max_memory: Option<Bound<'py, PyAny>>,
            raw: Option<bool>,
            decimate: Option<Bound<'py, PyAny>>,
            min_component: Option<f64>,
            mesh_aabb: Option<Vec<f32>>,
            volume_scope: Option<String>,
            $($then: $then_ty,)*
            $($files: $files_ty,)*
        ) -> $ret {
            let $options = $crate::settings::Overrides {
                cell,
                field,
                engine,
                normals,
                correct,
                block,
                threads,
                max_memory,
                raw,
                decimate,
                min_component,
                mesh_aabb,
                volume_scope,
                $($files,)*
                ..Default::default()
            };
            $body
        }
    };
}
pub(crate) use options_function;

/// The keyword arguments that override the configuration; None leaves its value.
#[derive(Default)]
pub struct Overrides<'py> {
    pub spacing: Option<f32>,
    pub cell: Option<Bound<'py, PyAny>>,
    pub field: Option<String>,
    pub engine: Option<String>,
    pub normals: Option<String>,
    pub correct: Option<i64>,
    pub block: Option<i64>,
    pub threads: Option<i64>,
    pub max_memory: Option<Bound<'py, PyAny>>,
    pub raw: Option<bool>,
    pub decimate: Option<Bound<'py, PyAny>>,
    pub min_component: Option<f64>,
    pub mesh_aabb: Option<Vec<f32>>,
    pub volume_scope: Option<String>,
    pub particle_aabb: Option<Vec<f32>>,
    pub format: Option<String>,
    pub up_axis: Option<String>,
    /// Attribute names: a str (`"velocity,density"`) or a list of str.
    pub attributes: Option<Bound<'py, PyAny>>,
    pub temporal: Option<bool>,
}

/// `config` (None, a TOML file's path or a dict) with `overrides` applied, validated.
pub fn resolve(config: Option<&Bound<'_, PyAny>>, overrides: Overrides<'_>) -> PyResult<Config> {
    let config = match config {
        None => Config::default(),
        Some(c) => match c.cast::<PyDict>() {
            Ok(dict) => from_dict(dict)?,
            Err(_) => {
                let path: PathBuf = c.extract().map_err(|_| {
                    PyTypeError::new_err(format!(
                        "config must be a TOML file's path or a dict, got {}",
                        type_name(c)
                    ))
                })?;
                Config::from_file(&path).map_err(to_py)?
            }
        },
    };
    let o = overrides;
    let length = |value: Bound<'_, PyAny>, key: &str| match value.extract::<String>() {
        Ok(text) => Length::parse(&text).map_err(to_py),
        Err(_) => Ok(Length::World(value.extract().map_err(|_| {
            PyTypeError::new_err(format!(
                "{key} must be a length such as \"r/2\" or a number"
            ))
        })?)),
    };
    let aabb = |b: Option<Vec<f32>>, key: &str| match b {
        None => Ok(None),
        Some(b) => Some(<[f32; 6]>::try_from(b.as_slice()).map_err(|_| {
            PyValueError::new_err(format!(
                "{key} must be six numbers (min x, min y, min z, max x, max y, max z), got {}",
                b.len()
            ))
        }))
        .transpose(),
    };
    // Counts: a negative or huge one is refused naming its keyword; out-of-range ones by
    // validate, naming the key.
    let count = |n: Option<i64>, key: &str, what: &str| -> PyResult<Option<u32>> {
        n.map(|n| {
            u32::try_from(n)
                .map_err(|_| PyValueError::new_err(format!("{key} must be {what}, got {n}")))
        })
        .transpose()
    };
    let decimate = o.decimate.map(|d| length(d, "decimate")).transpose()?;
    let cell = o.cell.map(|c| length(c, "cell")).transpose()?;
    let threads = match o.threads {
        None => None,
        Some(n) => Some(usize::try_from(n).ok().filter(|&n| n > 0).ok_or_else(|| {
            PyValueError::new_err(format!("threads must be at least 1, got {n}"))
        })?),
    };
    let max_memory = match o.max_memory {
        None => None,
        Some(m) => Some(match m.extract::<String>() {
            Ok(text) => Bytes::parse(&text).map_err(to_py)?,
            Err(_) => Bytes(m.extract().map_err(|_| {
                PyTypeError::new_err(
                    "max_memory must be a size such as \"8G\" or a number of bytes",
                )
            })?),
        }),
    };
    let attributes = match attribute_names(o.attributes.as_ref())? {
        None => None,
        Some(names) => Some(OutputConfig::parse_attributes(&names).map_err(to_py)?),
    };
    fn parsed<T>(
        text: Option<String>,
        parse: impl Fn(&str) -> splash_sph::Result<T>,
    ) -> PyResult<Option<T>> {
        text.as_deref().map(parse).transpose().map_err(to_py)
    }
    let overrides = splash_sph::Overrides {
        field: o.field,
        spacing: o.spacing,
        cell,
        engine: parsed(o.engine, Engine::parse)?,
        normals: parsed(o.normals, Normals::parse)?,
        correct: count(o.correct, "correct", "from 0 to 32 Newton steps")?,
        block: count(o.block, "block", "from 1 to 4096 cubes")?,
        threads,
        max_memory,
        format: parsed(o.format, MeshFormat::parse)?,
        up_axis: parsed(o.up_axis, UpAxis::parse)?,
        attributes,
        particle_aabb: aabb(o.particle_aabb, "particle_aabb")?,
        raw: o.raw,
        mesh_aabb: aabb(o.mesh_aabb, "mesh_aabb")?,
        min_component: o.min_component,
        decimate,
        temporal: o.temporal,
        volume_scope: parsed(o.volume_scope, VolumeScope::parse)?,
    };
    config.apply(&overrides).map_err(to_py)
}

/// `attributes` as one comma-separated list: a str, or a list of names.
fn attribute_names(attributes: Option<&Bound<'_, PyAny>>) -> PyResult<Option<String>> {
    let Some(a) = attributes else {
        return Ok(None);
    };
    if let Ok(text) = a.extract::<String>() {
        return Ok(Some(text));
    }
    let names: Vec<String> = a.extract().map_err(|_| {
        PyTypeError::new_err("attributes must be names: a list of str or \"velocity,density\"")
    })?;
    Ok(Some(names.join(",")))
}

/// A configuration from a dict shaped like the TOML file (tables as nested dicts; None leaves a
/// key unset). Unknown keys are errors naming the key, as in a file.
fn from_dict(dict: &Bound<'_, PyDict>) -> PyResult<Config> {
    let text = toml::to_string(&table(dict)?)
        .map_err(|e| PyValueError::new_err(format!("config: {e}")))?;
    Config::from_toml(&text).map_err(|e| to_py(e.context("config")))
}

fn table(dict: &Bound<'_, PyDict>) -> PyResult<toml::Table> {
    let mut table = toml::Table::new();
    for (key, value) in dict.iter() {
        let key: String = key.extract().map_err(|_| {
            PyTypeError::new_err(format!("config keys must be strings, got {key:?}"))
        })?;
        if value.is_none() {
            continue;
        }
        let value = toml_value(&value).map_err(|e| {
            PyTypeError::new_err(format!("config key '{key}': {}", e.value(dict.py())))
        })?;
        table.insert(key, value);
    }
    Ok(table)
}

fn toml_value(value: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    // bool before int: Python's bools are ints.
    if value.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(value.extract()?));
    }
    if value.is_instance_of::<PyInt>() {
        return Ok(toml::Value::Integer(value.extract()?));
    }
    if value.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(value.extract()?));
    }
    if value.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(value.extract()?));
    }
    if let Ok(dict) = value.cast::<PyDict>() {
        return Ok(toml::Value::Table(table(dict)?));
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        return value
            .try_iter()?
            .map(|item| toml_value(&item?))
            .collect::<PyResult<_>>()
            .map(toml::Value::Array);
    }
    // numpy scalars and other numbers.
    if let Ok(i) = value.extract::<i64>() {
        return Ok(toml::Value::Integer(i));
    }
    if let Ok(f) = value.extract::<f64>() {
        return Ok(toml::Value::Float(f));
    }
    Err(PyTypeError::new_err(format!(
        "{} has no TOML equivalent",
        type_name(value)
    )))
}

/// The configuration as the dict that [`from_dict`] reads back.
pub fn to_dict<'py>(py: Python<'py>, config: &Config) -> PyResult<Bound<'py, PyAny>> {
    let table: toml::Table = toml::from_str(&config.to_toml())
        .map_err(|e| PyValueError::new_err(format!("config: {e}")))?;
    python_value(py, &toml::Value::Table(table))
}

fn python_value<'py>(py: Python<'py>, value: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        toml::Value::String(s) => s.into_pyobject(py)?.into_any(),
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Float(f) => f.into_pyobject(py)?.into_any(),
        toml::Value::Boolean(b) => b.into_pyobject(py)?.to_owned().into_any(),
        toml::Value::Datetime(d) => d.to_string().into_pyobject(py)?.into_any(),
        toml::Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(python_value(py, item)?)?;
            }
            list.into_any()
        }
        toml::Value::Table(table) => {
            let dict = PyDict::new(py);
            for (key, item) in table {
                dict.set_item(key, python_value(py, item)?)?;
            }
            dict.into_any()
        }
    })
}

fn type_name(value: &Bound<'_, PyAny>) -> String {
    value
        .get_type()
        .name()
        .map_or_else(|_| "?".to_string(), |n| n.to_string())
}
