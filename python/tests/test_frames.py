"""Every table as a polars DataFrame too (backend="polars"), with the same columns and values
as the pandas one; a bad backend named."""
import os

import numpy as np
import pytest

import physid
from conftest import ROOT, kuka_run
from test_identify import quiet_identify

pl = pytest.importorskip("polars")


def same(pandas_df, polars_df):
    assert isinstance(polars_df, pl.DataFrame)
    assert list(pandas_df.columns) == polars_df.columns
    assert len(pandas_df) == polars_df.height
    for c in pandas_df.columns:
        a, b = pandas_df[c].to_numpy(), polars_df[c].to_numpy()
        if a.dtype.kind in "fi":
            np.testing.assert_allclose(a.astype(float), b.astype(float), rtol=0, atol=0, equal_nan=True)
        else:
            assert [str(x) for x in a] == [str(x) for x in b], c


def test_identification_and_experiment_tables_in_polars(kuka):
    fit = quiet_identify(kuka, kuka_run(1), constraints="consistent")
    same(fit.bodies(), fit.bodies(backend="polars"))
    same(fit.joints(), fit.joints(backend="polars"))
    ex = physid.experiment(os.path.join(ROOT, "scenarios", "ci.toml"), seeds=1, threads=1)
    same(ex.rows(), ex.rows(backend="polars"))
    same(ex.summary(), ex.summary(backend="polars"))


def test_a_bad_backend_is_named(kuka):
    fit = quiet_identify(kuka, kuka_run(1), constraints="semi")
    with pytest.raises(ValueError, match="backend: 'arrow' is not one of pandas, polars"):
        fit.bodies(backend="arrow")
