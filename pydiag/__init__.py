"""pydiag: diagnose gear faults by fitting an FMU's fault parameters to a vibration spectrum.

The package is layered by pipeline stage, lowest first; a module imports only from its
own stage or lower ones (tests/test_layers.py checks it):

==========  ==============================================================================
core        errors, the bounded-parameter type, the measurement record
signal      amplitude spectra, noise floors, local maxima, synthetic noise, features
io          measurement files and the output policy for every file pydiag writes
fmu         FMU archives, descriptions, the plant, the compiled engine, worker isolation
gear        kinematics, named lines, the paper's features and classes, effect catalogue
model       adapters (what an FMU is to pydiag), records simulated from it, regression
fit         Eq. (12), the fit problem, particle swarm, the estimator
loop        compare, discover, the machine's own model and its loop, run history, report
diagnose    a fit classified, each fault group tested; every stage of a machine diagnosed
app         the command line and batch diagnosis
==========  ==============================================================================
"""

__version__ = "0.3.2"
