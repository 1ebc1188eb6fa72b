within GearDiag;
package Effects "GearPair plus one physical effect each: the candidates pydiag compare suggests"
  annotation(Documentation(info="<html>
<p>Each model extends GearDiag.GearPair and overrides one of its hooks
(k_mod, e_extra, F_extra, contact, acc_sensor, t_angle) with a modifier; new
parameters are declared in the model, those pydiag fits with min and max equal to
the range it searches. Each model is listed in package.order (which the Makefile
builds) and has one entry in pydiag/gear/effects.py, whose key (snake_case) the
JSON and the CLI use: docs/effects.md.</p></html>"));
end Effects;
