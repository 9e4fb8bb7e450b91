// A POV-Ray animation of a splash sequence: one mesh2 include per frame.
//   splash recon sim/ --format pov -o pov/
//   povray +Iscene.pov +W640 +H360 +KFI1 +KFF400            frames 1 to 400
//   povray +Iscene.pov +W640 +H360 +KFI100 +KFF400 +STP2    every 2nd: 100, 102, ..., 400
//   povray +Iscene.pov +W640 +H360 Declare=Frame=40         frame 40 alone (or +KFI40 +KFF40)
// Frame N includes pov/frame_NNNN.inc (4-digit padding, as splash names frames in an output
// directory). The include declares the object SplashMesh.
#version 3.7;
global_settings { assumed_gamma 1.0 }

// The frame: Frame when declared on the command line, else the animation's frame_number, which
// runs from +KFI to +KFF in steps of +STP and so is the number of the file. POV-Ray turns
// animation off for +KFI1 +KFF1 (as without +KFI and +KFF) and frame_number is then 0: frame 1.
#ifdef (Frame)
  #declare SplashFrame = Frame;
#elseif (clock_on)
  #declare SplashFrame = frame_number;
#else
  #declare SplashFrame = 1;
#end
#declare MeshFile = concat("pov/frame_", str(SplashFrame, -4, 0), ".inc");
#if (!file_exists(MeshFile))
  #error concat("no ", MeshFile, " for frame ", str(SplashFrame, 0, 0), ": is it in the sequence? (+STP gives the step between frame numbers)")
#end
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
