//! The three ways to treat the points a bitree mesh needs only to complete
//! the hierarchy: the one mode type of the workspace.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2.2: conforming (every needed point gets
//! its real height: the forced splits of ROAM/RTIN), fictitious (needed
//! points are interpolated on their diagonal and never transmitted; cota's
//! watertight reading also splits the other side, so there is no
//! T-junction), or fictitious as in the paper (hanging vertices). See
//! [`super::marks`] for the closure each mode applies.

use crate::mesh::check::CheckOptions;

/// How points needed only for the hierarchy are treated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// Every vertex carries its sample's real height; forced splits keep the
    /// mesh conforming. Default.
    #[default]
    Conforming,
    /// Points needed only to complete the hierarchy are fictitious: height
    /// interpolated at the midpoint of their diagonal, never transmitted.
    Fictitious {
        /// Also split the unsplit neighbour through each fictitious point (no
        /// T-junction, same surface). `false` is paper 000's faithful variant,
        /// with hanging vertices.
        watertight: bool,
    },
}

impl Mode {
    /// A short name for reports: `conforming`, `fictitious` or
    /// `fictitious-faithful`.
    pub fn name(&self) -> &'static str {
        match self {
            Mode::Conforming => "conforming",
            Mode::Fictitious { watertight: true } => "fictitious",
            Mode::Fictitious { watertight: false } => "fictitious-faithful",
        }
    }

    /// True when the mesh has no T-junction (everything but the faithful variant).
    pub const fn is_conforming(&self) -> bool {
        !matches!(self, Mode::Fictitious { watertight: false })
    }

    /// All three modes, in the order of their names above.
    pub const ALL: [Mode; 3] = [
        Mode::Conforming,
        Mode::Fictitious { watertight: true },
        Mode::Fictitious { watertight: false },
    ];

    /// What [`crate::check_mesh`] must verify of a mesh made in this mode
    /// with a vertical bound of `max_error_m` metres (`None`: no bound
    /// promised): conforming unless faithful, fictitious heights allowed
    /// unless conforming.
    pub const fn check_options(self, max_error_m: Option<f64>) -> CheckOptions {
        CheckOptions::DEFAULT
            .with_max_error_m(max_error_m)
            .with_conforming(self.is_conforming())
            .with_allow_fictitious(!matches!(self, Mode::Conforming))
    }
}
