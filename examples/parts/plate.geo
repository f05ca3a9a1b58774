// A 200 x 100 x 10 mm aluminium plate in millimetres, meshed unstructured by gmsh's
// defaults at 10 mm (ffrmbs preprocess ... --units si-mm). Physical groups: the volume
// "plate", its top face "top" (z = 10, the contact face) and the end face "clamp" (x = 0).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 200, 100, 10};
Physical Volume("plate") = {1};
Physical Surface("top") = Surface In BoundingBox{-0.1, -0.1, 9.9, 200.1, 100.1, 10.1};
Physical Surface("clamp") = Surface In BoundingBox{-0.1, -0.1, -0.1, 0.1, 100.1, 10.1};
Mesh.MeshSizeMax = 10;
