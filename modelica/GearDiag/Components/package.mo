within GearDiag;
package Components "Parts of a geared machine: its drive train and what lies between it and a sensor"
  annotation(Documentation(info="<html>
<p>The drive train, connected through Interfaces.Flange: SteadySpeed (the drive),
Inertia (a wheel, a hub, a rotor), Shaft (a shaft's torsional compliance), GearMesh (a
stage's mesh between its pinion's and its gear's shafts, the paper's law), LoadTorque.
Examples.TwoStageGearbox connects them.</p>
<p>Towards a sensor: HousingMode, one structural mode of the housing between a force and
an accelerometer; ShaftOrders, what a shaft does once or a few times a turn (unbalance,
misalignment, looseness), at its first ten orders, as a housing accelerometer sees it.</p></html>"));
end Components;
