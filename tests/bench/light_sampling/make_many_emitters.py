#!/usr/bin/env python3
# Usage: make_many_emitters.py QUADS_PER_SIDE OUT_DIR
# The bundled Cornell box with its ceiling light cut into QUADS_PER_SIDE^2
# quads (2 QUADS_PER_SIDE^2 emissive triangles of the same total power and
# lightmap chart): a scene whose direct light comes from many emitters.
import json
import os
import struct
import sys

K = int(sys.argv[1])
OUT = sys.argv[2]
os.makedirs(OUT, exist_ok=True)
ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', '..')
g=json.load(open(os.path.join(ROOT, 'scenes', 'cornell_box.gltf'))); buf=open(os.path.join(ROOT, 'scenes', 'cornell_box.bin'),'rb').read()
def read(acc_i):
    a=g['accessors'][acc_i]; bv=g['bufferViews'][a['bufferView']]
    off=bv.get('byteOffset',0)+a.get('byteOffset',0)
    n={'SCALAR':1,'VEC2':2,'VEC3':3}[a['type']]; fmt={5126:'f',5125:'I',5123:'H'}[a['componentType']]
    sz=struct.calcsize(fmt); stride=bv.get('byteStride',n*sz)
    return [struct.unpack_from('<'+fmt*n, buf, off+i*stride) for i in range(a['count'])]
p=g['meshes'][0]['primitives'][3]
P=read(p['attributes']['POSITION']); N=read(p['attributes']['NORMAL']); T0=read(p['attributes']['TEXCOORD_0']); T1=read(p['attributes']['TEXCOORD_1']); I=[i[0] for i in read(p['indices'])]
a,b,c=I[0],I[1],I[2]; d=[i for i in I[3:] if i not in (a,b,c)][0]
shared=[i for i in I[3:6] if i in (a,b,c)]; other=[i for i in (a,b,c) if i not in shared][0]
C=[other, shared[0], d, shared[1]]
def lerp(A,B,t): return tuple(x+(y-x)*t for x,y in zip(A,B))
def bil(arr,u,v): return lerp(lerp(arr[C[0]],arr[C[1]],u), lerp(arr[C[3]],arr[C[2]],u), v)
def cross(a,b): return (a[1]*b[2]-a[2]*b[1],a[2]*b[0]-a[0]*b[2],a[0]*b[1]-a[1]*b[0])
def sub(a,b): return tuple(x-y for x,y in zip(a,b))
verts=[];n0=[];t0=[];t1=[];idx=[]
for j in range(K+1):
    for i in range(K+1):
        u,v=i/K,j/K; verts.append(bil(P,u,v)); n0.append(N[C[0]]); t0.append(bil(T0,u,v)); t1.append(bil(T1,u,v))
orig=cross(sub(P[b],P[a]),sub(P[c],P[a]))
for j in range(K):
    for i in range(K):
        q=[j*(K+1)+i, j*(K+1)+i+1, (j+1)*(K+1)+i+1, (j+1)*(K+1)+i]
        for tri in ((q[0],q[1],q[2]),(q[0],q[2],q[3])):
            nn=cross(sub(verts[tri[1]],verts[tri[0]]),sub(verts[tri[2]],verts[tri[0]]))
            if sum(x*y for x,y in zip(nn,orig))<0: tri=(tri[0],tri[2],tri[1])
            idx+=tri
newbuf=bytearray(buf)
def add(data, fmt, n, typ, ctype, target):
    while len(newbuf)%4: newbuf.append(0)
    off=len(newbuf)
    for e in data: newbuf.extend(struct.pack('<'+fmt*n, *(e if n>1 else (e,))))
    g['bufferViews'].append({'buffer':0,'byteOffset':off,'byteLength':len(newbuf)-off,'target':target})
    acc={'bufferView':len(g['bufferViews'])-1,'componentType':ctype,'count':len(data),'type':typ}
    if typ=='VEC3' and fmt=='f':
        acc['min']=[min(e[k] for e in data) for k in range(3)]; acc['max']=[max(e[k] for e in data) for k in range(3)]
    g['accessors'].append(acc); return len(g['accessors'])-1
p['attributes']={'POSITION':add(verts,'f',3,'VEC3',5126,34962),'NORMAL':add(n0,'f',3,'VEC3',5126,34962),'TEXCOORD_0':add(t0,'f',2,'VEC2',5126,34962),'TEXCOORD_1':add(t1,'f',2,'VEC2',5126,34962)}
p['indices']=add(idx,'I',1,'SCALAR',5125,34963)
g['buffers'][0]['uri']='cornell_many.bin'; g['buffers'][0]['byteLength']=len(newbuf)
open(os.path.join(OUT, 'cornell_many.bin'),'wb').write(newbuf); json.dump(g,open(os.path.join(OUT, 'cornell_many.gltf'),'w'))
print(len(idx)//3,'emissive triangles')
