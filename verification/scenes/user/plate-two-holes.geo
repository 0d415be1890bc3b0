// A plate with two holes, 0.2 m × 0.1 m (x × y) with holes of radius 15 mm at x = 0.06 and
// x = 0.14 on its middle line, drawn with OpenCASCADE. The edges x = 0 and x = 0.2 are the
// physical groups "left" and "right"; the holes' walls are "holes".
SetFactory("OpenCASCADE");
Rectangle(1) = {0, 0, 0, 0.2, 0.1};
Disk(2) = {0.06, 0.05, 0, 0.015};
Disk(3) = {0.14, 0.05, 0, 0.015};
BooleanDifference(4) = { Surface{1}; Delete; }{ Surface{2, 3}; Delete; };
e = 1e-6;
Physical Curve("left") = Curve In BoundingBox{-e, -e, -e, e, 0.1 + e, e};
Physical Curve("right") = Curve In BoundingBox{0.2 - e, -e, -e, 0.2 + e, 0.1 + e, e};
Physical Curve("holes") = Curve In BoundingBox{0.045 - e, 0.035 - e, -e, 0.155 + e, 0.065 + e, e};
Physical Surface("plate") = {4};
