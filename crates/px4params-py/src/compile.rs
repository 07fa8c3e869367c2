//! Compiling the schema model (the dicts `px4params.dsdl_loader` produces) into one layout.

use std::collections::HashMap;

use px4params_core::compile::{BuildError, OwnedLayout};
use px4params_core::layout::{NodeId, Role};
use px4params_core::Cast;
use pyo3::intern;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};

use crate::errors::ModelError;

/// Compiles every type of `types` (key → type dict); returns the layout and each key's root.
pub fn compile_model(
    types: &Bound<'_, PyDict>,
) -> PyResult<(OwnedLayout, HashMap<String, NodeId>)> {
    let mut c = Compiler {
        types,
        layout: OwnedLayout::default(),
        roots: HashMap::new(),
        in_progress: Vec::new(),
    };
    for key in types.keys() {
        let key: String = key.extract()?;
        c.composite(&key)?;
    }
    Ok((c.layout, c.roots))
}

struct Compiler<'a, 'py> {
    types: &'a Bound<'py, PyDict>,
    layout: OwnedLayout,
    roots: HashMap<String, NodeId>,
    in_progress: Vec<String>,
}

/// `d[key]`. Keys are interned Python strings (`intern!`): their hashes are cached, where a
/// `&str` key would make and hash a new string on every look-up.
fn item<'py>(
    d: &Bound<'py, PyDict>,
    key: &Bound<'py, PyString>,
    what: &str,
) -> PyResult<Bound<'py, PyAny>> {
    d.get_item(key)?.ok_or_else(|| {
        let key = key.to_string();
        ModelError::NoEntry { what, key }.into()
    })
}

fn build_err(what: &str) -> impl FnOnce(BuildError) -> PyErr + '_ {
    move |err| ModelError::Layout { what, err }.into()
}

impl Compiler<'_, '_> {
    fn composite(&mut self, key: &str) -> PyResult<NodeId> {
        if let Some(&id) = self.roots.get(key) {
            return Ok(id);
        }
        if self.in_progress.iter().any(|k| k == key) {
            return Err(ModelError::Recursive { key }.into());
        }
        let def = self
            .types
            .get_item(key)?
            .ok_or_else(|| PyErr::from(ModelError::UnknownType { key }))?;
        let def = def.cast_into::<PyDict>()?;
        self.in_progress.push(key.to_owned());
        let kind: String = item(&def, intern!(def.py(), "kind"), key)?.extract()?;
        // p_version holds the minor version: one major version is one parameter type.
        let version: Option<u32> = match def.get_item(intern!(def.py(), "version"))? {
            Some(v) if !v.is_none() => Some(v.get_item(1)?.extract()?),
            _ => None,
        };
        let dialect: String = match def.get_item(intern!(def.py(), "dialect"))? {
            Some(d) => d.extract()?,
            None => "dsdl".into(),
        };
        let fields = item(&def, intern!(def.py(), "fields"), key)?.cast_into::<PyList>()?;
        let mut members: Vec<(String, NodeId, Role)> = Vec::with_capacity(fields.len());
        for f in fields.iter() {
            let f = f.cast_into::<PyDict>()?;
            let name: String = item(&f, intern!(f.py(), "name"), key)?.extract()?;
            let ty = item(&f, intern!(f.py(), "type"), key)?.cast_into::<PyDict>()?;
            let what = format!("{key}.{name}");
            let node = self.ty(&ty, &what)?;
            let is_void = ty
                .get_item(intern!(ty.py(), "kind"))?
                .is_some_and(|k| k.eq("void").unwrap_or(false));
            let role = if is_void {
                Role::Padding
            } else if name == "p_version" && dialect == "dsdl" {
                Role::Version(version.unwrap_or(0))
            } else {
                Role::Data
            };
            members.push((name, node, role));
        }
        let id = if kind == "union" {
            let variants: Vec<(&str, NodeId)> =
                members.iter().map(|(n, id, _)| (n.as_str(), *id)).collect();
            self.layout.union(&variants).map_err(build_err(key))?
        } else {
            let fields: Vec<(&str, NodeId, Role)> = members
                .iter()
                .map(|(n, id, r)| (n.as_str(), *id, *r))
                .collect();
            self.layout.structure(&fields).map_err(build_err(key))?
        };
        self.in_progress.pop();
        self.roots.insert(key.to_owned(), id);
        Ok(id)
    }

    fn ty(&mut self, ty: &Bound<'_, PyDict>, what: &str) -> PyResult<NodeId> {
        let kind: String = item(ty, intern!(ty.py(), "kind"), what)?.extract()?;
        let bits = || -> PyResult<u32> { item(ty, intern!(ty.py(), "bits"), what)?.extract() };
        let cast = || -> PyResult<Cast> {
            match ty.get_item(intern!(ty.py(), "cast"))? {
                Some(c) if c.eq("truncated")? => Ok(Cast::Truncated),
                _ => Ok(Cast::Saturated),
            }
        };
        let l = &mut self.layout;
        let built = match kind.as_str() {
            "uint" => l.uint(bits()?, cast()?),
            "int" => l.int(bits()?, cast()?),
            "float" => l.float(bits()?, cast()?),
            "bool" => Ok(l.boolean()),
            "void" => l.void(bits()?),
            "array" | "dynarray" => {
                let elem = item(ty, intern!(ty.py(), "elem"), what)?.cast_into::<PyDict>()?;
                let elem = self.ty(&elem, what)?;
                if kind == "array" {
                    let len: u32 = item(ty, intern!(ty.py(), "len"), what)?.extract()?;
                    self.layout.array(elem, len)
                } else {
                    let max: u32 = item(ty, intern!(ty.py(), "max"), what)?.extract()?;
                    self.layout.dyn_array(elem, max)
                }
            }
            "ref" => {
                let name: String = item(ty, intern!(ty.py(), "name"), what)?.extract()?;
                return self.composite(&name);
            }
            other => {
                let kind = other.to_owned();
                return Err(ModelError::UnknownKind { what, kind }.into());
            }
        };
        built.map_err(build_err(what))
    }
}
