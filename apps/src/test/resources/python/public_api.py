# Lists the public functions, classes and methods of a Python module file, read with ast (no import, so no package
# needs installing): one line each, "name(arguments)<TAB>result". apps.zeromq.PythonReadmeSpec compares them with the
# tables of apps/python/README.md.
import ast, sys
tree = ast.parse(open(sys.argv[1]).read())
classes = {n.name: n for n in tree.body if isinstance(n, ast.ClassDef)}
def sig(f, name):
    a = f.args
    names = [x.arg for x in a.posonlyargs + a.args if x.arg != "self"]
    if a.vararg: names.append("*" + a.vararg.arg)
    names += [x.arg for x in a.kwonlyargs]
    if a.kwarg: names.append("**" + a.kwarg.arg)
    ret = ast.unparse(f.returns) if f.returns is not None else "?"
    return "%s(%s)\t%s" % (name, ", ".join(names), ret)
def methods(c):
    found = {}
    for b in c.bases:
        if isinstance(b, ast.Name) and b.id in classes:
            found.update(methods(classes[b.id]))
    for n in c.body:
        if isinstance(n, ast.FunctionDef) and (not n.name.startswith("_") or n.name == "__init__"):
            found[n.name] = n
    return found
rows = set()
for n in tree.body:
    if isinstance(n, ast.FunctionDef) and not n.name.startswith("_"):
        rows.add(sig(n, n.name))
for name, c in classes.items():
    if name.startswith("_") or any(isinstance(b, ast.Name) and b.id == "Exception" for b in c.bases):
        continue
    for m, f in methods(c).items():
        rows.add(sig(f, name).split("\t")[0] + "\t" + name if m == "__init__" else sig(f, m))
for r in sorted(rows): print(r)
