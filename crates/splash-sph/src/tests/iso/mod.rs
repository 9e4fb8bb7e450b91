//! `splash iso`: analytic fields, components and λ2.

mod analytic;
mod iso_components;
mod lambda2;
