within GearDiag.Effects;
model PinionShaftOrders "The pinion shaft's own vibration at its first ten orders reaches the sensor"
  // Unbalance, misalignment, a coupling or a looseness of the pinion's shaft make lines
  // at its orders that the mesh does not (GearDiag.Components.ShaftOrders), added to what
  // the acc sensor sees of the mesh. The mesh itself (disp) does not feel them.
  extends GearDiag.GearPair(acc_sensor = der(v) + shaft.a);
  parameter Real A_s1(unit="m/s2", min=0) = 0 "Pinion shaft order 1 at the sensor";
  parameter Real A_s2(unit="m/s2", min=0) = 0 "Pinion shaft order 2 at the sensor";
  parameter Real A_s3(unit="m/s2", min=0) = 0 "Pinion shaft order 3 at the sensor";
  parameter Real A_s4(unit="m/s2", min=0) = 0 "Pinion shaft order 4 at the sensor";
  parameter Real A_s5(unit="m/s2", min=0) = 0 "Pinion shaft order 5 at the sensor";
  parameter Real A_s6(unit="m/s2", min=0) = 0 "Pinion shaft order 6 at the sensor";
  parameter Real A_s7(unit="m/s2", min=0) = 0 "Pinion shaft order 7 at the sensor";
  parameter Real A_s8(unit="m/s2", min=0) = 0 "Pinion shaft order 8 at the sensor";
  parameter Real A_s9(unit="m/s2", min=0) = 0 "Pinion shaft order 9 at the sensor";
  parameter Real A_s10(unit="m/s2", min=0) = 0 "Pinion shaft order 10 at the sensor";
  GearDiag.Components.ShaftOrders shaft(f_shaft = f_pinion, t_angle = t_angle,
    A_1 = A_s1, A_2 = A_s2, A_3 = A_s3, A_4 = A_s4, A_5 = A_s5,
    A_6 = A_s6, A_7 = A_s7, A_8 = A_s8, A_9 = A_s9, A_10 = A_s10)
    "The pinion shaft, seen at the sensor";
  annotation(Documentation(info="<html>
<p>The pinion shaft's own vibration at its first ten orders reaches the sensor.</p>
<pre>
Unbalance, misalignment, a coupling or a looseness of the pinion's shaft make lines
at its orders that the mesh does not (GearDiag.Components.ShaftOrders), added to what
the acc sensor sees of the mesh. The mesh itself (disp) does not feel them.
</pre>
</html>"));
end PinionShaftOrders;
