//! Surface recognition from rubbing and scratching: Nakano's roughness and friction features
//! with a 1-D self-organizing map, and Sinapov's spectrotemporal features with k-NN and a one-vs-one SVC; recognizer
//! files ([`model`]) train, store and evaluate either.
//!
//! May import `capture` (the data contract) and `svm` (the solvers), no other palpus crate.
pub mod category;
pub mod eval;
pub mod knn;
pub mod model;
pub mod nakano;
pub mod protocol;
pub mod som;
pub mod spectral;
pub mod svc;
