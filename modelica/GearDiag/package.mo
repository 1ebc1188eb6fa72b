within ;
package GearDiag "Gear models for FMU-based vibration diagnosis: the paper's pair, its effects, a gearbox's components"
  constant Real pi = 3.141592653589793 "The Modelica Standard Library is not available offline, so constants live here";

  annotation(Documentation(info="<html>
<p>GearPair: translational SDOF mesh with periodic time-varying stiffness, one faulty
pinion tooth, assembly and geometric transmission errors. Effects/ holds models that
extend GearPair with one extra physical effect each. Interfaces/ holds the flange
connector and the mesh's law GearPair shares with Components.GearMesh; Components/ the
parts of a drive train (drive, inertia, shaft, mesh, load) and what lies between it and a
sensor; Examples/ machines connected from them.</p></html>"));
end GearDiag;
