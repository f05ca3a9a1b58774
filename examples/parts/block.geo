// A 30 x 30 x 15 mm aluminium block in millimetres, meshed unstructured by gmsh at 10 mm
// (ffrmbs preprocess ... --units si-mm --order 1). Physical groups: the volume "block" and
// its bottom face "bottom" (z = 0), the face it lands on.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 30, 30, 15};
Physical Volume("block") = {1};
Physical Surface("bottom") = Surface In BoundingBox{-0.1, -0.1, -0.1, 30.1, 30.1, 0.1};
Mesh.MeshSizeMax = 10;
