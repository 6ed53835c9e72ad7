"""Accuracy of the integrator versus step size, the justification of the default step
(`stabctl.studies.convergence.step_accuracy_report`): reports/step_accuracy.md.

Run: python analysis/step_accuracy.py
"""

from stabctl.studies.convergence import step_accuracy_report

if __name__ == "__main__":
    print(step_accuracy_report("reports/step_accuracy.md"))
