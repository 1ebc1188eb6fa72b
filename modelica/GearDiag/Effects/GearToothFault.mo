within GearDiag.Effects;
model GearToothFault "A faulty tooth on the driven gear: extra stiffness variation once per gear turn"
  // Gear tooth 0 meshes once every Ng mesh cycles; the extra amplitude (a_g - a0) rides on
  // the same wave sigma, so the stiffness stays continuous at tooth changes.
  extends GearDiag.GearPair(k_mod = if mod(floor(f_mesh*time + 0.25), Ng) < 0.5
                                    then (a_g - a0)*sigma else 0);
  parameter Real a_g(min=0, max=0.9) = 0.3 "Stiffness variation amplitude of the faulty gear tooth";
end GearToothFault;
