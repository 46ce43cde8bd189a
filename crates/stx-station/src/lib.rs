//! The stx ground station: holds the drone link(s), runs the same estimator, guidance and
//! landing predictor as the drone on the live telemetry, keeps the mission's state and serves
//! the dashboard and the API described in `API.md`.
