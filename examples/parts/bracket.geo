// An L-shaped steel bracket in millimetres (ffrmbs preprocess ... --units si-mm):
// a 60 x 40 x 5 mm flange on the z = 0 plane and a 5 x 40 x 40 mm web at x = 0.
// Physical groups: the volume "bracket" and the flange's underside "base" (z = 0),
// the face to clamp.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 60, 40, 5};
Box(2) = {0, 0, 0, 5, 40, 40};
v() = BooleanUnion{ Volume{1}; Delete; }{ Volume{2}; Delete; };
Physical Volume("bracket") = v();
base() = Surface In BoundingBox{-0.1, -0.1, -0.1, 60.1, 40.1, 0.1};
Physical Surface("base") = base();
