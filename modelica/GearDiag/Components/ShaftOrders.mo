within GearDiag.Components;
model ShaftOrders "Vibration at the first ten orders of a shaft's speed, as a housing accelerometer sees it"
  // What a shaft itself does once or a few times a turn (an unbalance at 1x, a
  // misalignment at 1x and 2x, a coupling, a bent shaft or a looseness up to about 10x)
  // passes through its bearings into the housing. Those lines lie far below the mesh's
  // resonance, where its own response is small, and the sensor sees them added to what
  // it sees of the mesh:
  //   a = sum_k A_k*cos(k*w),   w = 2*pi*f_shaft*t_angle
  // Phases are not modelled: a spectrum shows amplitudes, and the mesh's own lines at
  // these orders are far weaker.
  parameter Real f_shaft(unit="Hz") = 25 "Shaft speed";
  parameter Real A_1(unit="m/s2") = 0 "Amplitude of order 1 at the sensor";
  parameter Real A_2(unit="m/s2") = 0 "Amplitude of order 2 at the sensor";
  parameter Real A_3(unit="m/s2") = 0 "Amplitude of order 3 at the sensor";
  parameter Real A_4(unit="m/s2") = 0 "Amplitude of order 4 at the sensor";
  parameter Real A_5(unit="m/s2") = 0 "Amplitude of order 5 at the sensor";
  parameter Real A_6(unit="m/s2") = 0 "Amplitude of order 6 at the sensor";
  parameter Real A_7(unit="m/s2") = 0 "Amplitude of order 7 at the sensor";
  parameter Real A_8(unit="m/s2") = 0 "Amplitude of order 8 at the sensor";
  parameter Real A_9(unit="m/s2") = 0 "Amplitude of order 9 at the sensor";
  parameter Real A_10(unit="m/s2") = 0 "Amplitude of order 10 at the sensor";
  input Real t_angle(unit="s") "Shaft angle over its mean speed";
  output Real a(unit="m/s2") "Acceleration at the sensor";
protected
  Real w(unit="rad") = 2*GearDiag.pi*f_shaft*t_angle "Shaft angle";
equation
  a = A_1*cos(1*w)
    + A_2*cos(2*w)
    + A_3*cos(3*w)
    + A_4*cos(4*w)
    + A_5*cos(5*w)
    + A_6*cos(6*w)
    + A_7*cos(7*w)
    + A_8*cos(8*w)
    + A_9*cos(9*w)
    + A_10*cos(10*w);
  annotation(Documentation(info="<html>
<p>Vibration at the first ten orders of a shaft's speed, as a housing accelerometer sees it.</p>
<pre>
What a shaft itself does once or a few times a turn (an unbalance at 1x, a
misalignment at 1x and 2x, a coupling, a bent shaft or a looseness up to about 10x)
passes through its bearings into the housing. Those lines lie far below the mesh's
resonance, where its own response is small, and the sensor sees them added to what
it sees of the mesh:
  a = sum_k A_k*cos(k*w),   w = 2*pi*f_shaft*t_angle
Phases are not modelled: a spectrum shows amplitudes, and the mesh's own lines at
these orders are far weaker.
</pre>
</html>"));
end ShaftOrders;
