# Tables for docs/results/ebslam3d.md from the whole-recording runs (JSON lines).
import json, sys, collections, statistics
def name(d):
    return d['groundtruth'].split('/')[-1].replace('rgbd_dataset_','').replace('-groundtruth.txt','').replace('motion:','')
ORDER=['freiburg1_xyz','freiburg1_desk','freiburg1_room','freiburg2_xyz','yaw_turn','shake','floor_sweep','orbit']
def load(files):
    rows=[]
    for f in files:
        for l in open(f):
            rows.append(json.loads(l))
    return rows
def main_table(rows, preset):
    by=collections.defaultdict(dict)
    for d in rows:
        if d['preset']!=preset or d.get('cover_at_s',-1)>=0: continue
        by[(name(d),d['imu'])][d['seed']]=d
    out=[]
    out.append('| path | IMU | RMSE seed 1 / 2 / 3 [cm] | mean [cm] | worst | > 5 cm | rot. RMSE mean [deg] | false alarm (mean) | miss (mean) | lost reports | x real time (min) | map + particles max [MiB] |')
    out.append('|---|---|---|---|---|---|---|---|---|---|---|---|')
    summary={}
    for imu in (False,True):
        allr=[]
        for p in ORDER:
            s=by.get((p,imu))
            if not s: continue
            r=[s[k]['rmse_m']*100 if k in s else None for k in (1,2,3)]
            have=[x for x in r if x is not None]
            allr+=have
            ds=list(s.values())
            cell=' / '.join(('**%.2f**' % x if x>5 else '%.2f' % x) if x is not None else '-' for x in r)
            out.append('| %s | %s | %s | %.2f | %.2f | %d | %.1f | %.1f %% | %.1f %% | %d | %.1f | %.1f |' % (
                p, 'yes' if imu else 'no', cell, statistics.mean(have), max(have), sum(x>5 for x in have),
                statistics.mean(d['rotation_rmse_deg'] for d in ds),
                100*statistics.mean(d['false_alarm_share'] for d in ds), 100*statistics.mean(d['miss_share'] for d in ds),
                sum(d['lost_count'] for d in ds), min(d['realtime_factor'] for d in ds), max(d['peak_memory_bytes'] for d in ds)/2**20))
        if allr:
            summary[imu]=(len(allr), statistics.mean(allr), sum(x>5 for x in allr), max(allr))
    return out, summary
if __name__=='__main__':
    preset=sys.argv[1]; rows=load(sys.argv[2:])
    t,s=main_table(rows,preset)
    print('\n'.join(t))
    for imu,(n,m,dv,w) in s.items():
        print(f"\n{preset}, IMU {'yes' if imu else 'no'}: {n} runs, mean {m:.2f} cm, {dv} above 5 cm, worst {w:.2f} cm")
