within GearDiag;
package Components "Parts that sit between the gear mesh and a measurement"
  annotation(Documentation(info="<html>
<p>HousingMode: one structural mode of the gearbox housing, between the dynamic mesh
force and an accelerometer on the housing.</p>
<p>ShaftOrders: what a shaft does once or a few times a turn (unbalance, misalignment,
looseness), at its first ten orders, as a housing accelerometer sees it.</p></html>"));
end Components;
