//! sndt-host: std tools around `sndt-core`.
