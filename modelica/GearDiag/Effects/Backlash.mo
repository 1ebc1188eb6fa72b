within GearDiag.Effects;
model Backlash "Contact loss: the teeth separate when the mesh deflection turns negative"
  // A smooth contact factor (C-infinity, so no events): ~1 in contact, ~0 when the
  // deflection x - e is negative; delta_c sets the width of the transition, from a hard
  // contact (0.01 um) to the roughness of ground teeth (0.3 um). The teeth separate only
  // where the dynamic deflection outgrows the static one: with the mesh at a resonance.
  extends GearDiag.GearPair(contact = 0.5*(1 + tanh((x - e_ate - e_dte - e_extra)/delta_c)));
  parameter Real delta_c(unit="m", min=1e-12) = 0.1e-6 "Width of the contact transition";
  annotation(Documentation(info="<html>
<p>Contact loss: the teeth separate when the mesh deflection turns negative.</p>
<pre>
A smooth contact factor (C-infinity, so no events): ~1 in contact, ~0 when the
deflection x - e is negative; delta_c sets the width of the transition, from a hard
contact (0.01 um) to the roughness of ground teeth (0.3 um). The teeth separate only
where the dynamic deflection outgrows the static one: with the mesh at a resonance.
</pre>
</html>"));
end Backlash;
