//! Import of real anatomy: surface meshes (STL, OBJ, PLY, glTF/GLB) and the
//! landmarks files that place them in the pelvis frame.
