// A 200 x 40 x 10 mm aluminium plate in millimetres with a 12 mm through hole at its
// centre (x = 100, y = 20), meshed unstructured by gmsh at 5 mm, second order with the
// mid-edge nodes on the hole (ffrmbs preprocess ... --units si-mm). Physical groups: the
// volume "plate", its top face "top" (z = 10: a face with a hole, a trimmed contour), the
// hole's top rim "rim" (a circle: an edge contour), the end face "clamp" (x = 0) and the
// bottom face "bottom" (z = 0).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 200, 40, 10};
Cylinder(2) = {100, 20, -1, 0, 0, 12, 6};
v() = BooleanDifference{ Volume{1}; Delete; }{ Volume{2}; Delete; };
Physical Volume("plate") = v();
Physical Surface("top") = Surface In BoundingBox{-0.1, -0.1, 9.9, 200.1, 40.1, 10.1};
Physical Curve("rim") = Curve In BoundingBox{93.9, 13.9, 9.9, 106.1, 26.1, 10.1};
Physical Surface("clamp") = Surface In BoundingBox{-0.1, -0.1, -0.1, 0.1, 40.1, 10.1};
Physical Surface("bottom") = Surface In BoundingBox{-0.1, -0.1, -0.1, 200.1, 40.1, 0.1};
Mesh.MeshSizeMax = 5;
