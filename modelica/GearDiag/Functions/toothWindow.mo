within GearDiag.Functions;
function toothWindow "Stiffness loss of a weaker tooth over its contact: deeper while it carries the load alone"
  input Real u "Mesh cycles since the start (f_mesh*t_angle)";
  input Integer n "Number of teeth on the wheel";
  input Real tooth "Index of the tooth";
  input Real width "Mesh cycles the tooth is in contact for: the contact ratio";
  input Real depth "Loss while the tooth is alone in contact over its loss in double contact";
  input Real ramp "Mesh cycles over which the load passes from one tooth pair to the next";
  output Real w "1 while the tooth is alone in contact, 1/depth in double contact, 0 out of contact";
protected
  Real s "Mesh cycles from the middle of the tooth's contact";
  Real x1 "Progress of the step into contact, 0..1";
  Real x2 "Progress of the step into single contact, 0..1";
algorithm
  // Tooth i carries the load alone around mesh cycle i + 1/2 of GearPair's clock, where its
  // stiffness wave is lowest (sigma = -1); it is in contact for `width` cycles centred
  // there, alone for the middle 2 - width of them. Each step is eased over `ramp` cycles
  // (x^2 (3 - 2 x): continuous with its first derivative, so the solver sees no jump).
  s := abs(mod(u - tooth - 0.5 + n/2, n) - n/2);
  x1 := min(max((width/2 + ramp/2 - s)/ramp, 0), 1);
  x2 := min(max((1 - width/2 + ramp/2 - s)/ramp, 0), 1);
  w := (x1*x1*(3 - 2*x1) + (depth - 1)*x2*x2*(3 - 2*x2))/depth;
  annotation(Documentation(info="<html>
<p>Stiffness loss of a weaker tooth over its contact: deeper while it carries the load alone.</p>
</html>"));
end toothWindow;
