//! Surface recognition from rubbing and scratching: Nakano's roughness and friction features
//! with a 1-D self-organizing map, and Sinapov's spectrotemporal features with k-NN.
pub mod eval;
pub mod knn;
pub mod nakano;
pub mod som;
pub mod spectral;
