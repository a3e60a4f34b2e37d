//! What a number in `history.csv` measures, and the case's name for its unit.

use crate::case::Units;

/// The physical quantity of a history column (dimensionless columns have none).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    Length,
    Force,
    Time,
    Temperature,
    Energy,
    /// A heat flow: energy per time.
    Power,
}

impl Quantity {
    /// As written in `summary.json` and on plot axes without `[units]`.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Length => "length",
            Quantity::Force => "force",
            Quantity::Time => "time",
            Quantity::Temperature => "temperature",
            Quantity::Energy => "energy",
            Quantity::Power => "power",
        }
    }

    pub const ALL: [Quantity; 6] = [
        Quantity::Length,
        Quantity::Force,
        Quantity::Time,
        Quantity::Temperature,
        Quantity::Energy,
        Quantity::Power,
    ];

    /// The unit the case names for this quantity, or makes from those it names (energy as
    /// force·length, power as energy/time); `None` where it names too few.
    pub fn unit(self, units: &Units) -> Option<String> {
        match self {
            Quantity::Length => units.length.clone(),
            Quantity::Force => units.force.clone(),
            Quantity::Time => units.time.clone(),
            Quantity::Temperature => units.temperature.clone(),
            Quantity::Energy => units.energy.clone().or_else(|| {
                Some(format!(
                    "{}·{}",
                    units.force.as_ref()?,
                    units.length.as_ref()?
                ))
            }),
            Quantity::Power => units.power.clone().or_else(|| {
                Some(format!(
                    "{}/{}",
                    Quantity::Energy.unit(units)?,
                    units.time.as_ref()?
                ))
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn energy_and_power_are_made_from_the_units_named() {
        let mut u = Units {
            length: Some("mm".into()),
            force: Some("N".into()),
            time: Some("s".into()),
            ..Units::default()
        };
        assert_eq!(Quantity::Energy.unit(&u).as_deref(), Some("N·mm"));
        assert_eq!(Quantity::Power.unit(&u).as_deref(), Some("N·mm/s"));
        u.energy = Some("mJ".into());
        assert_eq!(Quantity::Power.unit(&u).as_deref(), Some("mJ/s"));
        u.power = Some("mW".into());
        assert_eq!(Quantity::Power.unit(&u).as_deref(), Some("mW"));
        assert_eq!(Quantity::Temperature.unit(&u), None);
        u.force = None;
        u.energy = None;
        assert_eq!(Quantity::Energy.unit(&u), None);
    }
}
