// A 400 x 30 x 6 mm aluminium boom segment (a satellite arm's link) in millimetres,
// meshed unstructured by gmsh at 6 mm (ffrmbs preprocess ... --units si-mm). Physical
// groups: the volume "boom" and its top face "top" (z = 6, the contact face).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 400, 30, 6};
Physical Volume("boom") = {1};
Physical Surface("top") = Surface In BoundingBox{-0.1, -0.1, 5.9, 400.1, 30.1, 6.1};
Mesh.MeshSizeMax = 6;
