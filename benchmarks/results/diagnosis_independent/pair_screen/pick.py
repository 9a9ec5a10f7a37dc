import os; exec(open(os.path.join(os.path.dirname(os.path.abspath(__file__)), 'now.py')).read())
import collections
sets = collections.defaultdict(list); cnt=collections.Counter()
for c,(n,k) in cur.items():
    l = lst[c]; seed=c.split('_')[0]
    double = '+' in c.split('_',2)[-1]
    none = c.endswith('_none')
    if l in ('combos','pairs') or double or none or not k:
        sets[l].append(seed+'_'); cnt[l, 'double' if double else 'none' if none else 'miss']+=1
print(sorted(cnt.items()), sum(cnt.values()))
print(' '.join(f"{l}:{','.join(v)}" for l,v in sets.items()), file=open('sets.txt','w'))
tot=collections.Counter(lst.values()); print(tot, len(cur))
