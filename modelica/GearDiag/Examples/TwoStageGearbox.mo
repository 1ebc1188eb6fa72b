within GearDiag.Examples;
model TwoStageGearbox "Two stages on three shafts (the PHM 2009 spur gearbox's 32/96 and 48/80), one housing accelerometer"
  // drive -> mesh1 -> gear1 ... idler shaft ... pinion2 -> mesh2 -> gear2 -> load.
  // The idler shaft's twist couples the stages: each stage's mesh force moves the other's
  // shafts. The accelerometer sees both mesh forces through the housing far above its
  // modes (each mesh's acc).
  parameter Real T_in(unit="N.m") = 20 "Input torque";
  GearDiag.Components.SteadySpeed drive "Input shaft at its steady speed";
  GearDiag.Components.GearMesh mesh1(Np = 32, Ng = 96, f_pinion = 30, r_p = 0.032, T = T_in)
    "First stage";
  GearDiag.Components.Inertia gear1(J = 4e-3) "First stage's gear";
  GearDiag.Components.Shaft idler(k_t = 2e5, d_t = 2, tau_0 = T_in*mesh1.r_g/mesh1.r_p)
    "Idler shaft between the stages";
  GearDiag.Components.Inertia pinion2(J = 1e-3) "Second stage's pinion";
  GearDiag.Components.GearMesh mesh2(Np = 48, Ng = 80, f_pinion = mesh1.f_pinion*mesh1.Np/mesh1.Ng,
    r_p = 0.048, T = idler.tau_0) "Second stage";
  GearDiag.Components.Inertia gear2(J = 5e-3) "Second stage's gear and the output shaft";
  GearDiag.Components.LoadTorque load(T = mesh2.T*mesh2.r_g/mesh2.r_p) "Output load";
  output Real acc(unit="m/s2") "Housing acceleration at the sensor";
  output Real disp_1(unit="m") "First stage's deflection";
  output Real disp_2(unit="m") "Second stage's deflection";
equation
  connect(drive.flange, mesh1.flange_a);
  connect(mesh1.flange_b, gear1.flange_a);
  connect(gear1.flange_b, idler.flange_a);
  connect(idler.flange_b, pinion2.flange_a);
  connect(pinion2.flange_b, mesh2.flange_a);
  connect(mesh2.flange_b, gear2.flange_a);
  connect(gear2.flange_b, load.flange);
  acc = mesh1.acc + mesh2.acc;
  disp_1 = mesh1.disp;
  disp_2 = mesh2.disp;
  annotation(Documentation(info="<html>
<p>Two stages on three shafts (the PHM 2009 spur gearbox's 32/96 and 48/80), one housing accelerometer.</p>
<pre>
drive -&gt; mesh1 -&gt; gear1 ... idler shaft ... pinion2 -&gt; mesh2 -&gt; gear2 -&gt; load.
The idler shaft's twist couples the stages: each stage's mesh force moves the other's
shafts. The accelerometer sees both mesh forces through the housing far above its
modes (each mesh's acc).
</pre>
</html>"));
end TwoStageGearbox;
