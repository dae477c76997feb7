"""The shared library of the post-processing scripts (scripts/*.py are its command-line front ends).

    paths       the repository root, the solver binary, paths as the runs see them
    mpirun      running bin/signorini under mpiexec: MPI environment, time limit, log, log tail
    runs        reading HDF5 outputs: /run attributes, vertex fields, solve history, contact data
    studyfile   validating YAML study files: StudyError, key checks, numbers, names, options
    rates       convergence rates: level rates, least-squares fits, agreement, monotone-until-floor
    pareto      cost-error analysis: usable runs, dominance, Pareto fronts, recommendations
    formatting  numbers as text in tables and sentences
    report      CSV, Markdown and text-file writers
    figures     PNG figures: pyplot on the Agg backend, saving, the note of an empty log plot
    exact       closed forms (the mms solution) and an accurate P1 error quadrature, independent of the C code

Front ends put the scripts directory on sys.path and import the modules they need, e.g.
`from signorini.studyfile import StudyError`.
"""
