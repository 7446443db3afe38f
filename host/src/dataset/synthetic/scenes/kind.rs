//! The kinds of room the generator knows.

/// The kinds of room the generator knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SceneKind {
    /// Sofa, TV, coffee table, bookshelf, lamps.
    LivingRoom,
    /// Bed, night stands, dresser, wardrobe.
    Bedroom,
    /// Counters, cabinets, sink, refrigerator, dining table.
    Kitchen,
    /// Desks, chairs, monitors, whiteboard, shelves.
    Office,
    /// Bathtub, toilet, sink, mirror, towels.
    Bathroom,
    /// A large space (up to 15 m) with living, dining, kitchen and work zones.
    OpenPlan,
}

impl SceneKind {
    /// All kinds, in the order the generator cycles through them.
    pub const ALL: [SceneKind; 6] = [
        SceneKind::LivingRoom,
        SceneKind::Bedroom,
        SceneKind::Kitchen,
        SceneKind::Office,
        SceneKind::Bathroom,
        SceneKind::OpenPlan,
    ];

    /// Short name used in scene names.
    pub fn name(self) -> &'static str {
        match self {
            SceneKind::LivingRoom => "living",
            SceneKind::Bedroom => "bedroom",
            SceneKind::Kitchen => "kitchen",
            SceneKind::Office => "office",
            SceneKind::Bathroom => "bathroom",
            SceneKind::OpenPlan => "openplan",
        }
    }
}
