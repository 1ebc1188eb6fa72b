within GearDiag;
package Effects "GearPair plus one physical effect each: the candidates pydiag compare suggests"
  annotation(Documentation(info="<html>
<p>Each model extends GearDiag.GearPair and overrides one of its hooks
(k_mod, e_extra, F_extra, contact) with a modifier; new parameters are declared
in the model. The keys used by pydiag (JSON, CLI) are the snake_case names in
pydiag/effects.py.</p></html>"));
end Effects;
