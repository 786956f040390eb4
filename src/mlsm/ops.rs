//! The linear differential operators a shape function can approximate, and sets of them.

use serde::Serialize;

/// One scalar operator evaluated at a node: `u`, `du/dx`, ..., `d2u/dy2`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Op {
    /// `u(p)` (interpolation).
    Value,
    /// `du/dx`.
    Dx,
    /// `du/dy`.
    Dy,
    /// `d2u/dx2`.
    Dxx,
    /// `d2u/dxdy`.
    Dxy,
    /// `d2u/dy2`.
    Dyy,
}

impl Op {
    /// All operators, in storage order.
    pub const ALL: [Op; 6] = [Op::Value, Op::Dx, Op::Dy, Op::Dxx, Op::Dxy, Op::Dyy];

    /// Derivative order (0, 1 or 2).
    pub fn order(self) -> i32 {
        match self {
            Op::Value => 0,
            Op::Dx | Op::Dy => 1,
            Op::Dxx | Op::Dxy | Op::Dyy => 2,
        }
    }

    /// Derivative multi-index `(a, b)` of `d^(a+b) / dx^a dy^b`.
    pub fn multi_index(self) -> (u32, u32) {
        match self {
            Op::Value => (0, 0),
            Op::Dx => (1, 0),
            Op::Dy => (0, 1),
            Op::Dxx => (2, 0),
            Op::Dxy => (1, 1),
            Op::Dyy => (0, 2),
        }
    }

    fn bit(self) -> u8 {
        1 << (self as u8)
    }
}

/// A set of operators (a bit set over [`Op`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct OpSet(u8);

impl OpSet {
    /// No operator.
    pub const EMPTY: OpSet = OpSet(0);
    /// `u` only.
    pub const VALUE: OpSet = OpSet(1);
    /// First derivatives `d/dx, d/dy`.
    pub const D1: OpSet = OpSet(0b110);
    /// Second derivatives `d2/dx2, d2/dxdy, d2/dy2`.
    pub const D2: OpSet = OpSet(0b111000);

    /// Whether `op` is in the set.
    pub fn contains(self, op: Op) -> bool {
        self.0 & op.bit() != 0
    }

    /// Whether the set is empty.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Operators in the set, in storage order.
    pub fn iter(self) -> impl Iterator<Item = Op> {
        Op::ALL.into_iter().filter(move |o| self.contains(*o))
    }

    /// Number of operators in the set.
    pub fn len(self) -> usize {
        self.0.count_ones() as usize
    }

    /// Names of the operators, for the run summary.
    pub fn names(self) -> Vec<&'static str> {
        self.iter()
            .map(|o| match o {
                Op::Value => "value",
                Op::Dx => "d/dx",
                Op::Dy => "d/dy",
                Op::Dxx => "d2/dx2",
                Op::Dxy => "d2/dxdy",
                Op::Dyy => "d2/dy2",
            })
            .collect()
    }
}

impl std::ops::BitOr for OpSet {
    type Output = OpSet;
    fn bitor(self, rhs: OpSet) -> OpSet {
        OpSet(self.0 | rhs.0)
    }
}

impl std::ops::BitOrAssign for OpSet {
    fn bitor_assign(&mut self, rhs: OpSet) {
        self.0 |= rhs.0;
    }
}

impl std::ops::BitAnd for OpSet {
    type Output = OpSet;
    fn bitand(self, rhs: OpSet) -> OpSet {
        OpSet(self.0 & rhs.0)
    }
}

impl From<Op> for OpSet {
    fn from(op: Op) -> OpSet {
        OpSet(op.bit())
    }
}
