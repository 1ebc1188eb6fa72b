within GearDiag.Effects;
model HousingSensor "The acceleration sensor sits on the housing, behind one housing mode"
  // The base model's acc is the mesh acceleration along the line of action; a real
  // accelerometer is on the housing. Here acc is the housing mode's response to the
  // dynamic mesh force (GearDiag.Components.HousingMode); disp stays the mesh's.
  extends GearDiag.GearPair(acc_sensor = housing.a);
  parameter Real f_housing(unit="Hz", min=1) = 2500 "Natural frequency of the housing mode";
  parameter Real zeta_housing(unit="1", min=1e-4, max=1) = 0.05 "Damping ratio of the housing mode";
  GearDiag.Components.HousingMode housing(f_n = f_housing, zeta = zeta_housing, m_h = m,
    F_0 = T/r_p, F = mesh_force) "Housing between the mesh and the sensor";
  annotation(Documentation(info="<html>
<p>The acceleration sensor sits on the housing, behind one housing mode.</p>
<pre>
The base model's acc is the mesh acceleration along the line of action; a real
accelerometer is on the housing. Here acc is the housing mode's response to the
dynamic mesh force (GearDiag.Components.HousingMode); disp stays the mesh's.
</pre>
</html>"));
end HousingSensor;
