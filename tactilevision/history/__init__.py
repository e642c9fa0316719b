"""Calibration history of each gel over days (``tactilevision history``).

Gels age, wear and tear; labs recalibrate. This subpackage gathers the output
folders of ``tactilevision calibrate`` (:func:`gather`, :func:`read_calibration`),
tabulates each sensor's calibrations (:func:`history_rows`,
:func:`write_history_csv`: date, E, nu, c, beta with their intervals, certified
and rejected presses, clock offset), fits the trend of E over days and says
whether the gel has left its first calibration's interval (:func:`assess`,
:func:`weighted_line`, :func:`relative_change`), diagnoses every press of the
gel pooled along the day (:func:`pooled_diagnosis`: ``aging`` or
``stiffness_step:day``), and draws it
(:func:`history_figures`, :func:`write_history_report`). The formats are in
``docs/formats.md`` ("Calibration history").
"""

from ._pooled import PooledDiagnosis, pooled_diagnosis, pooled_measurements
from ._read import CalibrationRecord, gather, read_calibration
from ._report import history_figures, write_history_report
from ._table import HISTORY_COLUMNS, history_rows, sensor_file_name, write_history_csv
from ._trend import Assessment, LineFit, assess, relative_change, weighted_line

__all__ = ["HISTORY_COLUMNS", "Assessment", "CalibrationRecord", "LineFit", "PooledDiagnosis",
           "assess", "gather", "history_figures", "history_rows", "pooled_diagnosis",
           "pooled_measurements", "read_calibration", "relative_change", "sensor_file_name",
           "weighted_line", "write_history_csv", "write_history_report"]
