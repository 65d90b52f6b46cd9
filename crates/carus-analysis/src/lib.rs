//! Reads a pose history and reports which cardinal movements of labour
//! happened, when and how large (CARDINAL_MOVEMENTS.md).
