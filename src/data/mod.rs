//! Flight-data schema, CSV and MAVLink readers/writers, units and validation.
