within GearDiag.Effects;
model Backlash "Contact loss: the teeth separate when the mesh deflection turns negative"
  // A smooth contact factor (C-infinity, so no events): ~1 in contact, ~0 when the
  // deflection x - e is negative; delta_c sets the width of the transition.
  extends GearDiag.GearPair(contact = 0.5*(1 + tanh((x - e_ate - e_dte - e_extra)/delta_c)));
  parameter Real delta_c(unit="m", min=1e-9) = 0.2e-6 "Width of the contact transition";
end Backlash;
