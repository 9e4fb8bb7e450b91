// A POV-Ray animation of a splash sequence: one mesh2 include per frame.
//   splash recon sim/ --format pov -o pov/
//   povray +Iscene.pov +W640 +H360 +KFI1 +KFF400
// frame_number runs from +KFI to +KFF; frame N includes pov/frame_NNNN.inc (4-digit padding, as
// splash names frames in an output directory). The include declares the object SplashMesh.
#version 3.7;
global_settings { assumed_gamma 1.0 }

#declare MeshFile = concat("pov/frame_", str(frame_number, -4, 0), ".inc");
#include MeshFile

camera {
  location <0.6, 0.9, -1.3>
  look_at <0.6, 0.2, 0.4>
  // POV-Ray's axes are left-handed; this mirrors the image back to the simulation's
  // right-handed axes (y up).
  right -x * image_width / image_height
}
light_source { <2, 4, -3> color rgb 1 }
background { color rgb <0.85, 0.9, 1.0> }
plane { y, 0 pigment { checker color rgb 0.9 color rgb 0.6 scale 0.1 } }
object {
  SplashMesh
  pigment { color rgb <0.2, 0.45, 0.9> }
  finish { phong 0.6 }
}
