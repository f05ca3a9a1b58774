// A 120 x 60 x 40 mm steel block in millimetres with a channel along x: a half
// cylinder of radius 25 mm whose axis runs along the top face's centre line (y = 30,
// z = 40). Meshed unstructured by gmsh at 8 mm, second order with the mid-edge nodes
// on the channel (ffrmbs preprocess ... --units si-mm). Physical groups: the volume
// "block", the curved channel face "groove" and the bottom face "bottom" (z = 0).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 120, 60, 40};
Cylinder(2) = {0, 30, 40, 120, 0, 0, 25};
v() = BooleanDifference{ Volume{1}; Delete; }{ Volume{2}; Delete; };
Physical Volume("block") = v();
Physical Surface("groove") = Surface In BoundingBox{-0.1, 4.9, 14.9, 120.1, 55.1, 40.1};
Physical Surface("bottom") = Surface In BoundingBox{-0.1, -0.1, -0.1, 120.1, 60.1, 0.1};
Mesh.MeshSizeMax = 8;
