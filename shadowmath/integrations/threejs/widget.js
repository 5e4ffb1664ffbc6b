// The ShadowWidget's view (anywidget). three.js and shadowmath.js arrive as strings in the
// widget's state (three_source, module_source) and are imported from Blob URLs: nothing is
// loaded from the network, and a notebook saved with its widget state draws offline.

const cache = {};
async function importSource(source) {
	if (!cache[source.length]) {
		const url = URL.createObjectURL(new Blob([source], { type: 'text/javascript' }));
		cache[source.length] = import(url);
	}
	return cache[source.length];
}

function buildLight(THREE, spec) {
	let light;
	if (spec.kind === 'directional') light = new THREE.DirectionalLight(0xffffff, 3);
	else if (spec.kind === 'spot') light = new THREE.SpotLight(0xffffff, 30, 0, spec.angle, 0.05, 0);
	else light = new THREE.PointLight(0xffffff, 30, 0, 0);
	light.position.fromArray(spec.position);
	if (light.target) light.target.position.fromArray(spec.target || [0, 0, 0]);
	light.castShadow = true;
	light.shadow.normalBias = 0.02; // the floor casts and receives: no acne on it
	return light;
}

function buildMeshes(THREE, meshes) {
	return meshes.map((m) => {
		const geometry = new THREE.BufferGeometry();
		geometry.setAttribute('position', new THREE.Float32BufferAttribute(m.positions, 3));
		geometry.setIndex(m.indices);
		geometry.computeVertexNormals();
		const mesh = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({ color: m.color, side: THREE.DoubleSide }));
		mesh.castShadow = true;
		mesh.receiveShadow = true;
		return mesh;
	});
}

async function render({ model, el }) {
	const THREE = await importSource(model.get('three_source'));
	const sm = await importSource(model.get('module_source'));
	const width = el.clientWidth || 640;
	const height = model.get('height');
	const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
	renderer.setSize(width, height);
	renderer.shadowMap.enabled = true;
	el.appendChild(renderer.domElement);
	const status = document.createElement('div');
	status.style.font = '12px sans-serif';
	el.appendChild(status);

	const scene = new THREE.Scene();
	scene.background = new THREE.Color(0xf4f4f4);
	scene.add(new THREE.AmbientLight(0xffffff, 0.35));
	const camera = new THREE.PerspectiveCamera(45, width / height, 0.05, 500);
	camera.up.set(0, 0, 1);
	const view = model.get('camera');
	camera.position.fromArray(view.position);
	const orbit = new THREE.OrbitControls(camera, renderer.domElement);
	orbit.target.fromArray(view.target);
	orbit.update();
	orbit.addEventListener('end', () => { // the viewer's camera, back to Python
		model.set('camera', { position: camera.position.toArray(), target: orbit.target.toArray() });
		model.save_changes();
	});

	let meshes = [];
	let light = null;
	let helper = null;
	let gizmo = null;
	const mapView = new THREE.Mesh(new THREE.PlaneGeometry(1, 1), new THREE.MeshBasicMaterial());
	const hud = new THREE.Scene();
	hud.add(mapView);
	const hudCamera = new THREE.OrthographicCamera(0, 1, 1, 0, -1, 1);

	function rebuildMeshes() {
		meshes.forEach((m) => scene.remove(m));
		meshes = buildMeshes(THREE, model.get('meshes'));
		meshes.forEach((m) => scene.add(m));
	}

	function rebuildLight() {
		if (light) { scene.remove(light); if (light.target) scene.remove(light.target); light.dispose(); }
		if (gizmo) { scene.remove(gizmo.getHelper()); gizmo.dispose(); }
		light = buildLight(THREE, model.get('light'));
		scene.add(light);
		if (light.target) scene.add(light.target);
		gizmo = new THREE.TransformControls(camera, renderer.domElement);
		gizmo.attach(light);
		gizmo.addEventListener('dragging-changed', (e) => {
			orbit.enabled = !e.value;
			if (!e.value) {
				model.set('light', { ...model.get('light'), position: light.position.toArray() });
				model.save_changes();
			}
		});
		scene.add(gizmo.getHelper());
		applyFit();
	}

	function applyFit() {
		const data = model.get('shadow');
		sm.removeShadow(light);
		if (model.get('fitted') && data && data.type) sm.applyShadow(light, data);
		if (helper) { scene.remove(helper); helper.dispose(); helper = null; }
		if (model.get('show_frustum') && !light.isPointLight) {
			helper = new THREE.CameraHelper(light.shadow.camera);
			scene.add(helper);
		}
		status.textContent = model.get('fit_error') || (model.get('fitted') ? 'fitted shadow camera' : "three.js's default shadow camera");
	}

	function frame() {
		if (!el.isConnected && renderer.domElement.parentNode !== el) return;
		orbit.update();
		if (helper) helper.update();
		renderer.autoClear = true;
		renderer.render(scene, camera);
		const map = light && light.shadow.map;
		if (model.get('show_map') && map && !light.isPointLight) {
			mapView.material.map = map.texture;
			mapView.material.needsUpdate = true;
			const s = Math.min(width, height) / 3;
			renderer.autoClear = false;
			renderer.setViewport(width - s - 8, 8, s, s);
			mapView.position.set(0.5, 0.5, 0);
			renderer.render(hud, hudCamera);
			renderer.setViewport(0, 0, width, height);
		}
		requestAnimationFrame(frame);
	}

	rebuildMeshes();
	rebuildLight();
	model.on('change:meshes', rebuildMeshes);
	model.on('change:shadow', applyFit);
	model.on('change:fitted', applyFit);
	model.on('change:show_frustum', applyFit);
	model.on('change:light', () => {
		const spec = model.get('light');
		if (spec.kind !== (light.isDirectionalLight ? 'directional' : light.isSpotLight ? 'spot' : 'point')) rebuildLight();
		else light.position.fromArray(spec.position);
	});
	window.__shadowmathWidget = { renderer, scene, camera, get light() { return light; } };
	requestAnimationFrame(frame);
	return () => { renderer.dispose(); };
}

export default { render };
