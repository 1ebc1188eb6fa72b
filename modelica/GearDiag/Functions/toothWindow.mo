within GearDiag.Functions;
function toothWindow "Smooth bump over the mesh cycles one tooth of a wheel is in contact for"
  input Real u "Mesh cycles since the start (f_mesh*t_angle)";
  input Integer n "Number of teeth on the wheel";
  input Real tooth "Index of the tooth (real: the bump moves smoothly with it)";
  input Real width "Mesh cycles the tooth is in contact for: the contact ratio";
  output Real w "1 in the middle of the tooth's contact, 0 out of contact";
protected
  Real s "Mesh cycles since the tooth came into contact, modulo a turn of the wheel";
algorithm
  // Tooth i meshes in the cycle [i - 1/4, i + 3/4) of GearPair's toothIndex; a tooth is in
  // contact for `width` cycles centred on that cycle, loading and unloading as sin^2
  // (continuous with its first derivative: the solver sees no step).
  s := mod(u - tooth - 0.25 + width/2, n);
  w := if s < width then sin(GearDiag.pi*s/width)^2 else 0;
end toothWindow;
