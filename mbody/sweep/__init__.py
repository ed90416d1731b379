"""Many runs of one model: a sweep's cases (`grid`), what each computes (`runs`), the
results file (`table`), and the chunks run on Dask or in this process (`cluster`, the only
module that imports dask)."""
