within GearDiag.Effects;
model OtherShaftOrders "Another shaft's own vibration at its first ten orders reaches the sensor"
  // A shaft of the machine beyond the gear pair (a motor's behind a first stage, a second
  // stage's output) turns at r_other times the pinion's speed. Its unbalance,
  // misalignment or looseness make lines at its orders that the pair does not
  // (GearDiag.Components.ShaftOrders), added to what the acc sensor sees of the mesh. The
  // mesh itself (disp) does not feel them. r_other is not fitted: the machine's
  // kinematics set it (pydiag: --other-shaft).
  extends GearDiag.GearPair(acc_sensor = der(v) + shaft.a);
  parameter Real r_other(unit="1", min=0) = 1 "Speed of the other shaft over the pinion's";
  parameter Real A_o1(unit="m/s2", min=0) = 0 "Other shaft order 1 at the sensor";
  parameter Real A_o2(unit="m/s2", min=0) = 0 "Other shaft order 2 at the sensor";
  parameter Real A_o3(unit="m/s2", min=0) = 0 "Other shaft order 3 at the sensor";
  parameter Real A_o4(unit="m/s2", min=0) = 0 "Other shaft order 4 at the sensor";
  parameter Real A_o5(unit="m/s2", min=0) = 0 "Other shaft order 5 at the sensor";
  parameter Real A_o6(unit="m/s2", min=0) = 0 "Other shaft order 6 at the sensor";
  parameter Real A_o7(unit="m/s2", min=0) = 0 "Other shaft order 7 at the sensor";
  parameter Real A_o8(unit="m/s2", min=0) = 0 "Other shaft order 8 at the sensor";
  parameter Real A_o9(unit="m/s2", min=0) = 0 "Other shaft order 9 at the sensor";
  parameter Real A_o10(unit="m/s2", min=0) = 0 "Other shaft order 10 at the sensor";
  GearDiag.Components.ShaftOrders shaft(f_shaft = r_other*f_pinion, t_angle = t_angle,
    A_1 = A_o1, A_2 = A_o2, A_3 = A_o3, A_4 = A_o4, A_5 = A_o5,
    A_6 = A_o6, A_7 = A_o7, A_8 = A_o8, A_9 = A_o9, A_10 = A_o10)
    "The other shaft, seen at the sensor";
  annotation(Documentation(info="<html>
<p>Another shaft's own vibration at its first ten orders reaches the sensor.</p>
<pre>
A shaft of the machine beyond the gear pair (a motor's behind a first stage, a second
stage's output) turns at r_other times the pinion's speed. Its unbalance,
misalignment or looseness make lines at its orders that the pair does not
(GearDiag.Components.ShaftOrders), added to what the acc sensor sees of the mesh. The
mesh itself (disp) does not feel them. r_other is not fitted: the machine's
kinematics set it (pydiag: --other-shaft).
</pre>
</html>"));
end OtherShaftOrders;
