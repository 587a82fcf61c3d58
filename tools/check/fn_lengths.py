"""Longest functions in a Rust source tree, by brace matching (issue 34: none over 150 lines in src/).

    python3 tools/check/fn_lengths.py src

Comments and string literals are blanked before counting braces; a brace inside a raw string can skew a count."""
import re, os, sys
root = sys.argv[1]
out = []
for d, _, fs in os.walk(root):
    for f in fs:
        if not f.endswith('.rs'): continue
        p = os.path.join(d, f); lines = open(p).read().split('\n')
        i = 0
        while i < len(lines):
            m = re.match(r'\s*(pub(\([^)]*\))?\s+)?(const\s+)?(async\s+)?(unsafe\s+)?fn\s+(\w+)', lines[i])
            if m:
                depth = 0; started = False; j = i
                while j < len(lines):
                    code = re.sub(r'//.*', '', lines[j])
                    code = re.sub(r'"([^"\\]|\\.)*"', '""', code)
                    code = re.sub(r"'([^'\\]|\\.)'", "''", code)
                    depth += code.count('{') - code.count('}')
                    if '{' in code: started = True
                    if started and depth <= 0: break
                    if not started and code.strip().endswith(';'): break
                    j += 1
                if started: out.append((j - i + 1, p, i + 1, m.group(6)))
            i += 1
out.sort(reverse=True)
for n, p, l, name in out[:8]: print(n, p, l, name)
print('over 150:', sum(1 for o in out if o[0] > 150))
