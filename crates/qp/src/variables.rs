//! Named decision variables.

use std::ops::Range;

use crate::error::QpError;

/// Handle of one named decision variable inside a [`VariableSet`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct VarId(pub(crate) usize);

impl VarId {
    /// Index of the variable in declaration order (0 for the first `add`).
    pub fn index(self) -> usize {
        self.0
    }
}

/// An ordered list of named decision variables; the QP vector `x` is their concatenation in declaration order.
///
/// ```
/// use stride_qp::VariableSet;
/// let mut vars = VariableSet::new();
/// let base = vars.add("base_velocity", 6).unwrap();
/// let joints = vars.add("joint_velocities", 23).unwrap();
/// assert_eq!(vars.range(joints), 6..29);
/// assert_eq!(vars.total_size(), 29);
/// assert_eq!(vars.id("base_velocity"), Some(base));
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VariableSet {
    names: Vec<String>,
    offsets: Vec<usize>,
    sizes: Vec<usize>,
    total: usize,
}

impl VariableSet {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends a variable block of `size` scalars called `name`; returns its handle.
    ///
    /// Errors: [`QpError::DuplicateVariable`] if the name exists, [`QpError::EmptyVariable`] if `size == 0`.
    pub fn add(&mut self, name: &str, size: usize) -> Result<VarId, QpError> {
        if self.id(name).is_some() {
            return Err(QpError::DuplicateVariable {
                name: name.to_owned(),
            });
        }
        if size == 0 {
            return Err(QpError::EmptyVariable {
                name: name.to_owned(),
            });
        }
        let id = VarId(self.names.len());
        self.names.push(name.to_owned());
        self.offsets.push(self.total);
        self.sizes.push(size);
        self.total += size;
        Ok(id)
    }

    /// The handle of the variable called `name`, if any.
    pub fn id(&self, name: &str) -> Option<VarId> {
        self.names.iter().position(|n| n == name).map(VarId)
    }

    /// Whether `id` belongs to this set.
    pub fn contains(&self, id: VarId) -> bool {
        id.0 < self.names.len()
    }

    /// Index range of the variable inside `x`.
    ///
    /// # Panics
    /// If `id` was not created by this set (a programming error, like an out-of-bounds index).
    pub fn range(&self, id: VarId) -> Range<usize> {
        self.offsets[id.0]..self.offsets[id.0] + self.sizes[id.0]
    }

    /// Size of the variable (see [`VariableSet::range`] for panics).
    pub fn size(&self, id: VarId) -> usize {
        self.sizes[id.0]
    }

    /// Name of the variable (see [`VariableSet::range`] for panics).
    pub fn name(&self, id: VarId) -> &str {
        &self.names[id.0]
    }

    /// Total number of scalar decision variables (the length of `x`).
    pub fn total_size(&self) -> usize {
        self.total
    }

    /// Number of named variables.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// True when no variable was added.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// Iterates over `(id, name, range)` in declaration order.
    pub fn iter(&self) -> impl Iterator<Item = (VarId, &str, Range<usize>)> + '_ {
        (0..self.names.len()).map(move |i| (VarId(i), self.names[i].as_str(), self.range(VarId(i))))
    }
}
