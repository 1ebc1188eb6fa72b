within GearDiag.Effects;
model SecondPinionToothFault "A second faulty pinion tooth"
  extends GearDiag.GearPair(k_mod = if abs(toothIndex - tooth2) < 0.5 then (a_f2 - a0)*sigma else 0);
  parameter Real a_f2(min=0, max=0.9) = 0.3 "Stiffness variation amplitude of the second faulty tooth";
  parameter Real tooth2 = 5 "Index of the second faulty pinion tooth (0 is the first)";
end SecondPinionToothFault;
