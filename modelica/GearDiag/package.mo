within ;
package GearDiag "Gear-pair models for FMU-based vibration diagnosis"
  constant Real pi = 3.141592653589793 "The Modelica Standard Library is not available offline, so constants live here";

  annotation(Documentation(info="<html>
<p>GearPair: translational SDOF mesh with periodic time-varying stiffness, one faulty
pinion tooth, assembly and geometric transmission errors. Effects/ holds models that
extend GearPair with one extra physical effect each.</p></html>"));
end GearDiag;
