within GearDiag;
package Interfaces "Connectors and the shared law of the gear models"
  annotation(Documentation(info="<html>
<p>Flange: a shaft's end (speed over the steady speed, torque), the connector of the
drive train's components.</p>
<p>PartialMeshLaw: the mesh's parameters, stiffness and transmission errors, which
GearPair (the paper's pair) and Components.GearMesh (a stage between two shafts) share.</p></html>"));
end Interfaces;
