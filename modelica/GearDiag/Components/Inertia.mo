within GearDiag.Components;
model Inertia "A rigid rotating body (a wheel, a hub, a rotor) between two flanges"
  //   J*w' = flange_a.tau + flange_b.tau,   w the body's speed over its steady speed
  parameter Real J(unit="kg.m2", min=0) = 1e-3 "Moment of inertia about the shaft's axis";
  GearDiag.Interfaces.Flange flange_a "One end";
  GearDiag.Interfaces.Flange flange_b "The other end";
  Real w(unit="rad/s", start=0, fixed=true, nominal=1e-2) "Speed over the steady speed";
equation
  flange_a.w = w;
  flange_b.w = w;
  J*der(w) = flange_a.tau + flange_b.tau;
  annotation(Documentation(info="<html>
<p>A rigid rotating body (a wheel, a hub, a rotor) between two flanges.</p>
<pre>
  J*w' = flange_a.tau + flange_b.tau,   w the body's speed over its steady speed
</pre>
</html>"));
end Inertia;
