// A 0.1 × 0.05 m plate meshed with triangles; the edge x = 0 is the physical group "left".
SetFactory("OpenCASCADE");
Rectangle(1) = {0, 0, 0, 0.1, 0.05};
e = 1e-6;
Physical Curve("left") = Curve In BoundingBox{-e, -e, -e, e, 0.05 + e, e};
